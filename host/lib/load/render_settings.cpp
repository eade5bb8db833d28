#include "load/render_settings.h"

#include "util/error.h"

#include <exception>
#include <string>

namespace et {
namespace {

template <typename E> struct Named {
    E value;
    const char* name;
};
constexpr Named<Strategy> kStrategies[] = {{Strategy::light, "light"},
                                           {Strategy::bsdf, "bsdf"},
                                           {Strategy::mis, "mis"},
                                           {Strategy::uniform, "uniform"},
                                           {Strategy::sis, "sis"},
                                           {Strategy::compensated, "compensated"},
                                           {Strategy::visibility, "visibility"},
                                           {Strategy::cosine, "cosine"},
                                           {Strategy::automatic, "auto"},
                                           {Strategy::lights, "lights"}};
constexpr Named<MisHeuristic> kHeuristics[] = {{MisHeuristic::automatic, "auto"},
                                               {MisHeuristic::balance, "balance"},
                                               {MisHeuristic::power, "power"}};
constexpr Named<SamplerKind> kSamplers[] = {{SamplerKind::sobol, "sobol"},
                                            {SamplerKind::random, "random"}};
constexpr Named<BsdfSampling> kBsdfSamplings[] = {
    {BsdfSampling::automatic, "auto"}, {BsdfSampling::ndf, "ndf"}, {BsdfSampling::vndf, "vndf"}};
constexpr Named<LightBatch> kLightBatches[] = {
    {LightBatch::automatic, "auto"}, {LightBatch::on, "on"}, {LightBatch::off, "off"}};
constexpr Named<FilmSumsAt> kFilmSums[] = {
    {FilmSumsAt::automatic, "auto"}, {FilmSumsAt::host, "host"}, {FilmSumsAt::device, "device"}};
constexpr Named<QueueCounts> kQueueCounts[] = {
    {QueueCounts::automatic, "auto"}, {QueueCounts::host, "host"}, {QueueCounts::device, "device"}};
constexpr Named<Backend> kBackends[] = {{Backend::opencl, "opencl"}, {Backend::cpu, "cpu"}};

template <typename E, size_t N> const char* name_in(const Named<E> (&table)[N], E v) {
    for (const auto& n : table)
        if (n.value == v)
            return n.name;
    return "?";
}

template <typename E, size_t N>
std::vector<std::string> names_in(const Named<E> (&table)[N], size_t count = N) {
    std::vector<std::string> out;
    for (size_t i = 0; i < count; ++i)
        out.push_back(table[i].name);
    return out;
}

// Names that were choices once, and why they are not: a scene or script that names one is told.
// Their measurements: docs/history/results-journal.md.
void refuse_retired(const std::string& s, const std::string& what, const char* kind) {
    if (std::string(kind) == "strategy" && s == "adaptive")
        throw Error(what + ": strategy 'adaptive' was retired (it measured 0.92-0.94x the "
                           "paper's MIS at equal time); use compensated, the default");
    if (std::string(kind) == "BSDF sampling" && s == "mix")
        throw Error(what + ": BSDF sampling 'mix' was retired (it cost 8-14% under broad light "
                           "for a tail it bounded in one scene); use vndf or ndf");
}

template <typename E, size_t N>
E parse_in(const Named<E> (&table)[N], const std::string& s, const std::string& what,
           const char* kind, size_t count = N) {
    refuse_retired(s, what, kind);
    for (size_t i = 0; i < count; ++i)
        if (s == table[i].name)
            return table[i].value;
    std::string choices;
    for (size_t i = 0; i < count; ++i)
        choices += (i ? ", " : "") + std::string(table[i].name);
    const std::string shown = s.size() > 40 ? s.substr(0, 40) + "..." : s;
    throw Error(what + ": unknown " + kind + " '" + shown + "' (use " + choices + ")");
}

constexpr size_t kUserStrategies = 9; // all but "lights"

} // namespace

const char* name_of(Strategy v) {
    return name_in(kStrategies, v);
}
const char* name_of(MisHeuristic v) {
    return name_in(kHeuristics, v);
}
const char* name_of(SamplerKind v) {
    return name_in(kSamplers, v);
}
const char* name_of(Backend v) {
    return name_in(kBackends, v);
}

const char* name_of(BsdfSampling v) {
    return name_in(kBsdfSamplings, v);
}
BsdfSampling parse_bsdf_sampling(const std::string& s, const std::string& what) {
    return parse_in(kBsdfSamplings, s, what, "BSDF sampling");
}
std::vector<std::string> bsdf_sampling_names() {
    return names_in(kBsdfSamplings);
}
const char* name_of(LightBatch v) {
    return name_in(kLightBatches, v);
}
LightBatch parse_light_batch(const std::string& s, const std::string& what) {
    return parse_in(kLightBatches, s, what, "light batch setting");
}
std::vector<std::string> light_batch_names() {
    return names_in(kLightBatches);
}
const char* name_of(FilmSumsAt v) {
    return name_in(kFilmSums, v);
}
FilmSumsAt parse_film_sums(const std::string& s, const std::string& what) {
    return parse_in(kFilmSums, s, what, "film sums setting");
}
std::vector<std::string> film_sums_names() {
    return names_in(kFilmSums);
}
const char* name_of(QueueCounts v) {
    return name_in(kQueueCounts, v);
}
QueueCounts parse_queue_counts(const std::string& s, const std::string& what) {
    return parse_in(kQueueCounts, s, what, "queue counts setting");
}
std::vector<std::string> queue_counts_names() {
    return names_in(kQueueCounts);
}
namespace {
// The MIS strategies beyond the paper's estimator: what `auto` gives them, it never gives `mis`.
bool beyond_the_paper(Strategy s) {
    return s == Strategy::compensated || s == Strategy::visibility || s == Strategy::cosine ||
           s == Strategy::automatic;
}
} // namespace

BsdfSampling resolved_bsdf_sampling(const RenderSettings& st) {
    if (st.bsdf_sampling != BsdfSampling::automatic)
        return st.bsdf_sampling;
    return beyond_the_paper(st.strategy) ? BsdfSampling::vndf : BsdfSampling::ndf;
}
MisHeuristic resolved_heuristic(const RenderSettings& st) {
    if (st.heuristic != MisHeuristic::automatic)
        return st.heuristic;
    return beyond_the_paper(st.strategy) ? MisHeuristic::balance : MisHeuristic::power;
}

int check_split_count(int n, const std::string& what) {
    if (n < 1 || n > ETK_MAX_SPLIT || (n & (n - 1)) != 0)
        throw Error(what + ": must be a power of two from 1 to " + std::to_string(ETK_MAX_SPLIT) +
                    " (got " + std::to_string(n) + ")");
    return n;
}

void check_split(const RenderSettings& st) {
    check_split_count(st.light_samples, "light samples per vertex");
    check_split_count(st.bsdf_samples, "BSDF samples per vertex");
    if ((st.light_samples != 1 || st.bsdf_samples != 1) && st.strategy != Strategy::mis)
        throw Error(std::string("light and BSDF samples per vertex (") +
                    std::to_string(st.light_samples) + ", " + std::to_string(st.bsdf_samples) +
                    ") split the mis strategy's samples (--light-samples / --bsdf-samples, or "
                    "the scene's render.light_samples / render.bsdf_samples); strategy '" +
                    name_of(st.strategy) + "' takes one of each (name the strategy mis to split)");
}

Strategy parse_strategy(const std::string& s, const std::string& what) {
    return parse_in(kStrategies, s, what, "strategy", kUserStrategies);
}
MisHeuristic parse_heuristic(const std::string& s, const std::string& what) {
    return parse_in(kHeuristics, s, what, "MIS heuristic");
}
SamplerKind parse_sampler(const std::string& s, const std::string& what) {
    return parse_in(kSamplers, s, what, "sampler");
}
Backend parse_backend(const std::string& s, const std::string& what) {
    return parse_in(kBackends, s, what, "back end");
}

std::vector<std::string> strategy_names() {
    return names_in(kStrategies, kUserStrategies);
}
std::vector<std::string> heuristic_names() {
    return names_in(kHeuristics);
}
std::vector<std::string> sampler_names() {
    return names_in(kSamplers);
}
std::vector<std::string> backend_names() {
    return names_in(kBackends);
}

} // namespace et
