#include "prepare/technique.h"

#include "kernels/light_sampling.h"
#include <cstdlib>

namespace et {

namespace {

struct Technique {
    int light_first, light_deeper; // ETK_LIGHT_*
    bool mis, continuation, thin_last_bsdf;
    int candidates_first = 1, candidates_deeper = 1; // light_resampling.h
};

// The compensated map serves only where a BSDF sample can reach the same direction (MIS, below
// the first vertex: Karlik et al. 2019). At the first vertex the sampler's points are
// stratified best, and the full map's smooth warp keeps that stratification where
// max(0, L - mean L) -- zero over most of the sphere, with an edge wherever L crosses its mean --
// breaks it: at equal samples on the efficiency suite at depth 1, compensating the first vertex
// too has 0.52-0.91x MIS's error, the full distribution there 1.02-1.08x; below it, where the
// points are padded, the compensated distribution's lower variance per sample wins (depth 5: up
// to 1.3x; docs/history/results-journal.md). Delta vertices draw no light sample, and rays they
// scatter count in full, so nothing needs the full distribution below the first vertex. A rough
// dielectric's BSDF sample reaches every direction of either hemisphere where it transmits or
// reflects anything, so the compensated distribution serves it over the whole sphere too.
Technique technique_of(Strategy s) {
    switch (s) {
    case Strategy::light:
        return {ETK_LIGHT_MAP, ETK_LIGHT_MAP, false, true, false};
    case Strategy::bsdf:
        return {ETK_LIGHT_NONE, ETK_LIGHT_NONE, false, true, false};
    case Strategy::mis:
        return {ETK_LIGHT_MAP, ETK_LIGHT_MAP, true, true, false};
    case Strategy::uniform:
        return {ETK_LIGHT_UNIFORM, ETK_LIGHT_UNIFORM, false, true, false};
    case Strategy::sis:
        return {ETK_LIGHT_STRATA, ETK_LIGHT_STRATA, false, false, false};
    case Strategy::compensated:
        return {ETK_LIGHT_MAP, ETK_LIGHT_COMPENSATED, true, true, true};
    case Strategy::lights:
        return {ETK_LIGHT_SET, ETK_LIGHT_SET, false, false, false};
    case Strategy::visibility:
    case Strategy::automatic:
        return {ETK_LIGHT_LEARNED, ETK_LIGHT_LEARNED, true, true, false};
    case Strategy::cosine:
        return {ETK_LIGHT_BINNED, ETK_LIGHT_COMPENSATED, true, true, true};
    case Strategy::resampled:
        return {ETK_LIGHT_MAP, ETK_LIGHT_COMPENSATED, true, true, true,
                getenv("ETK_CF") ? atoi(getenv("ETK_CF")) : 8, getenv("ETK_CD") ? atoi(getenv("ETK_CD")) : 8};
    }
    return {ETK_LIGHT_MAP, ETK_LIGHT_MAP, true, true, false};
}

} // namespace

void set_technique(etk::EtkParams& p, Strategy strategy) {
    const Technique t = technique_of(strategy);
    p.light_first = t.light_first;
    p.light_deeper = t.light_deeper;
    p.mis = t.mis ? 1 : 0;
    p.continuation = t.continuation ? 1 : 0;
    p.thin_last_bsdf = t.thin_last_bsdf ? 1 : 0;
    p.light_candidates_first = t.candidates_first;
    p.light_candidates_deeper = t.candidates_deeper;
}

bool technique_batches_light_samples(const etk::EtkParams& p) {
    return etk::etk_light_batches(p.light_first) && etk::etk_light_batches(p.light_deeper) &&
           p.light_candidates_first <= 1 && p.light_candidates_deeper <= 1;
}

bool technique_uses_light_set(const etk::EtkParams& p) {
    return p.light_first == ETK_LIGHT_SET;
}

} // namespace et
