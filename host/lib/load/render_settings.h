// How to render, as typed values: parsed once (scene file, then command line) and read by the
// renderer factory and the device parameters. Each enum's names live in one table here, used to
// parse, to print and to list the choices in --help.
#pragma once
#include "kernels/ggx.h"
#include "kernels/params.h"
#include "kernels/sampler.h"

#include <cstdint>
#include <string>
#include <vector>

namespace et {

// A strategy is a name for a set of the kernels' technique switches (kernels/params.h), which
// render/technique.h resolves; the name is what a user chooses.
enum class Strategy : int {
    light,       // one map sample per vertex
    bsdf,        // BSDF samples only
    mis,         // the paper's: one of each, combined by MIS
    uniform,     // uniform sphere directions (the baseline)
    sis,         // structured importance sampling, direct light only
    compensated, // MIS, light samples from the compensated map below the first vertex
    lights,      // a directional light set (--lights), never named by a user
    visibility,  // MIS, light samples guided by learned visibility
    cosine,      // MIS, light samples from the map x the cosine to the normal's bin
    automatic,   // "auto": visibility's learning, kept only where it beats compensated
};
// How GGX lobes are sampled (kernels/bsdf.h): automatic picks vndf for the strategies beyond the
// paper -- compensated, visibility, cosine -- and ndf, the paper's, for the others, so that
// `mis` stays the paper's estimator (visibility: equal-spp variance lower on every scene of the
// efficiency suite, by up to 21%, and on the five shipped scenes with GGX lobes, up to 12%, at
// the same time per sample: docs/history/results-journal.md, "The visibility strategy's verdict").
enum class BsdfSampling : int { automatic = -1, ndf = ETK_GGX_NDF, vndf = ETK_GGX_VNDF };
// The MIS weights (kernels/integrator.h): automatic picks power for mis, the project's choice
// for the paper's estimator, which every efficiency figure is relative to, and balance for the
// strategies beyond it -- compensated, visibility, cosine -- whose variance at equal samples it
// lowers (visibility: 8 of 9 shipped scenes; compensated: 19 of the efficiency suite's 20 scene
// pairs lower or equal: docs/history/results-journal.md, "The balance heuristic"). The others weigh
// nothing: power, unused.
enum class MisHeuristic : int {
    automatic = -1,
    balance = ETK_HEURISTIC_BALANCE,
    power = ETK_HEURISTIC_POWER
};
enum class SamplerKind : int { random = ETK_SAMPLER_RANDOM, sobol = ETK_SAMPLER_SOBOL };
enum class Backend : int { opencl, cpu };
// Whether the sample_lights stage draws the light samples in batches (kernels/integrator.h):
// automatic as the device prefers (WavefrontDevice::prefers_light_batches: natively yes, on
// OpenCL prefers_light_batches_on, render/executor_cl.h: CPUs yes, GPUs no). The same image
// either way.
enum class LightBatch : int { automatic, on, off };
// Where the film's exact sums (render/film_sums.h) take each pass: on the host, after the pass's
// film is read back, or on the device (OpenCL only: ClDevice::fold_film), read back only when
// the sums are asked for. automatic: on the device on a GPU, where the read-back and the host's
// fold took two thirds of a 2048x2048 pass. The same sums either way, bit for bit.
enum class FilmSumsAt : int { automatic, host, device };
// Where a wave's queue sizes are read (render/schedule.cpp, run_wave): by the host, after each
// bounce's intersect and shade launches, or on the device (OpenCL only: a bounce's launches are
// all enqueued at once, and each kernel reads its queue's size from the counters). automatic: on
// the device on a GPU, which otherwise idles at each read until the host launches again. The
// same image either way, bit for bit.
enum class QueueCounts : int { automatic, host, device };

const char* name_of(Strategy v);
const char* name_of(MisHeuristic v);
const char* name_of(SamplerKind v);
const char* name_of(Backend v);
const char* name_of(BsdfSampling v);
const char* name_of(LightBatch v);
const char* name_of(FilmSumsAt v);
const char* name_of(QueueCounts v);

// Throws et::Error "`what`: unknown strategy 'x' (use light, bsdf, ...)".
Strategy parse_strategy(const std::string& s, const std::string& what);
MisHeuristic parse_heuristic(const std::string& s, const std::string& what);
SamplerKind parse_sampler(const std::string& s, const std::string& what);
Backend parse_backend(const std::string& s, const std::string& what);
BsdfSampling parse_bsdf_sampling(const std::string& s, const std::string& what);
LightBatch parse_light_batch(const std::string& s, const std::string& what);
FilmSumsAt parse_film_sums(const std::string& s, const std::string& what);
QueueCounts parse_queue_counts(const std::string& s, const std::string& what);

// A split count ("`what`: must be a power of two from 1 to 64" otherwise).
int check_split_count(int n, const std::string& what);

// The names a user may give (for the command line's choices).
std::vector<std::string> strategy_names(); // without "lights", which --lights selects
std::vector<std::string> heuristic_names();
std::vector<std::string> sampler_names();
std::vector<std::string> backend_names();
std::vector<std::string> bsdf_sampling_names();
std::vector<std::string> light_batch_names();
std::vector<std::string> film_sums_names();
std::vector<std::string> queue_counts_names();

struct RenderSettings;
// bsdf_sampling with automatic resolved for the strategy.
BsdfSampling resolved_bsdf_sampling(const RenderSettings& st);
// heuristic with automatic resolved for the strategy.
MisHeuristic resolved_heuristic(const RenderSettings& st);
// Throws unless the split counts are powers of two up to ETK_MAX_SPLIT, and 1 unless the
// strategy is mis.
void check_split(const RenderSettings& st);

struct RenderSettings {
    // From the scene's "render" block, overridden by the command line.
    int spp = 16;
    // Deep enough for glass (in, out, and what lies behind) and for mirrors and metals to show
    // each other, as Cycles' default of 12; Russian roulette past rr_depth ends most paths long
    // before it. 1 is direct lighting only, the paper's setting, which a scene or the command line
    // names.
    int max_depth = 12;
    // auto: learns what blocks the map and keeps the tables only where its verdict measures that
    // they beat compensated on this image; its figures on the held-out set: docs/estimators.md.
    Strategy strategy = Strategy::automatic;
    MisHeuristic heuristic = MisHeuristic::automatic;
    SamplerKind sampler = SamplerKind::sobol;
    BsdfSampling bsdf_sampling = BsdfSampling::automatic;
    uint32_t seed = 1;
    double time_limit = 0.0; // seconds; 0: none
    // Russian roulette may end a path only past its first rr_depth surfaces (integrator.h): the
    // continuations of surfaces 1 .. rr_depth always go on. 5, one past Mitsuba 3's default (its
    // rr_depth 5 cuts from the fifth surface's continuation, this one's 4): in rooms lit
    // indirectly the second to fifth bounces carry much of the light, and cutting them by the
    // path's throughput cost more variance than the saved rays were worth
    // (docs/history/results-journal.md, "Russian roulette"). The build before cut from the
    // continuation of the third surface on (rr_depth 2 here).
    int rr_depth = 5;
    int paths = 0; // OpenCL paths in flight per lane; 0: the film over the lanes (ClDevice)
    // Splitting (Strategy::mis only): light and BSDF samples per vertex, powers of two up to
    // ETK_MAX_SPLIT (integrator.h, etk_split_samples). 1 and 1: the paper's estimator.
    int light_samples = 1, bsdf_samples = 1;
    // From the command line only.
    Backend backend = Backend::opencl;
    int device = 0;       // OpenCL device index
    int threads = 0;      // native threads; 0: all cores
    int sis_samples = 64; // SIS strata (Strategy::sis)
    std::string lights;   // directional light set file (Strategy::lights)
    bool aovs = false;    // keep the first hits' AOVs (render/film_aovs.h), written to the EXR
    // Draw the light samples of the strategies that allow it in the sample_lights stage, in
    // batches (kernels/integrator.h); off, the shade stage draws each: the same image.
    LightBatch light_batch = LightBatch::automatic;
    FilmSumsAt film_sums = FilmSumsAt::automatic;
    QueueCounts queue_counts = QueueCounts::automatic;
    // The visibility strategy's verdict (render/guide_verdict.h): after learning, measure its
    // tables against the paper's MIS on this image and keep the cheaper-per-error one.
    bool guide_verdict = true;
};

} // namespace et
