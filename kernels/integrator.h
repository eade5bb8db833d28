// The wavefront path tracer's stages, written once for the OpenCL kernels (wavefront.cl) and the
// native back end. Paths live in structure-of-arrays buffers indexed by slot; work queues are
// arrays of slots whose lengths are counters bumped atomically, so every stage runs over exactly
// the live work. One path per pixel per pass: film accumulation needs no atomics.
//
// Sample dimensions (pairs, regenerated from pixel, sample index, pair; never stored):
//   pair 0: pixel jitter; for bounce d: pair 1+3d light sample, 2+3d BSDF direction (at a
//   guided vertex: u.x also picks the guide or the BSDF, continuation_guide.h),
//   3+3d (BSDF lobe, Russian roulette); the adaptive strategy's technique choices and the
//   visibility strategy's choice to take the light sample: ETK_PAIR_SHARE + d (etk_shade). Split
//   samples (etk_split_samples) come from the same pairs shifted by a lattice. Pairs are hashed, so
//   these need not be contiguous.
#ifndef ETK_INTEGRATOR_H
#define ETK_INTEGRATOR_H
#include "aov.h"
#include "bsdf.h"
#include "bvh.h"
#include "compat.h"
#include "continuation_guide.h"
#include "portal_guide.h"
#include "directional_lights.h"
#include "envmap.h"
#include "film_accumulate.h"
#include "normal_bins.h"
#include "params.h"
#include "path_state.h"
#include "sampler.h"
#include "surface.h"
#include "visibility_guide.h"

ETK_BEGIN

// Every stage has this signature, so that one list (ETK_STAGES in path_state.h) generates the
// OpenCL kernels and the native back end's dispatch. i: index into the stage's queue; out: the
// queue pushes, which the caller makes after the stage returns (EtkPushes in path_state.h).
#define ETK_STAGE_PARAMS                                                                           \
    EtkScene S, EtkPaths P, EtkQueues Q, EtkFilm F, EtkParams p, int i, EtkPushes *out

ETK_FN float etk_mis_weight(int heuristic, float a, float b) {
    if (heuristic == ETK_HEURISTIC_POWER) {
        a *= a;
        b *= b;
    }
    return a + b > 0.0f ? a / (a + b) : 0.0f;
}

// The MIS weight of a light sample (density pl; p_bsdf pb there) and of a BSDF sample (pb; pl),
// each over its count: with nl = lc x p.light_samples light samples and nb = p.bsdf_samples BSDF
// samples expected per vertex (the mis strategy's splitting, etk_split_samples; lc < 1 where the
// visibility strategy takes its light sample with probability lc, etk_guide_light_count), the
// multi-sample heuristic's weight on nl pl and nb pb (Veach), divided by the technique's count.
// nl = nb = 1: the paper's weights, bit for bit.
// Forced inline: a call would copy EtkParams, as etk_dims would (surface.h).
ETK_FORCE_INLINE_FN float etk_light_sample_weight(EtkParams p, float lc, float pl, float pb) {
    float nl = lc * (float)p.light_samples;
    return etk_mis_weight(p.heuristic, nl * pl, (float)p.bsdf_samples * pb) / nl;
}
ETK_FORCE_INLINE_FN float etk_bsdf_sample_weight(EtkParams p, float lc, float pb, float pl) {
    float nb = (float)p.bsdf_samples;
    return etk_mis_weight(p.heuristic, nb * pb, lc * (float)p.light_samples * pl) / nb;
}

#define ETK_PAIR_SHARE 0x40000000u

// The first sample pair of a vertex at `depth` (its light sample; + 1 its BSDF direction, + 2 the
// lobe and Russian roulette: the layout above), for the shade stage and for sample_lights, which
// draws that light sample ahead of it.
ETK_FN uint etk_vertex_pair(int depth) {
    return 1u + 3u * (uint)depth;
}

// The distribution light samples are drawn from, and weighted by in MIS. The compensated one
// (Karlik et al. 2019) is used only where a BSDF sample can reach the same direction: the MIS
// strategies at non-delta vertices (the adaptive strategy keeps a BSDF share, below). Delta
// vertices draw no light sample, and rays they scatter count in full (etk_escaped), so
// nothing needs the full distribution in these strategies. A rough dielectric's BSDF sample
// reaches every direction of either hemisphere where it transmits or reflects anything
// (dielectric.h), so the compensated distribution serves it over the whole sphere too.
// The compensated strategy compensates from the path's second vertex on (`depth`: surface
// interactions before the vertex). At the first, the sampler's points are stratified best, and
// the full map's smooth warp keeps that stratification where max(0, L - mean L) -- zero over
// most of the sphere, with an edge wherever L crosses its mean -- breaks it: at equal samples on
// issue 10's suite at depth 1, compensating the first vertex too has 0.52-0.91x MIS's error, the
// full distribution there 1.02-1.08x; below it, where the points are padded, the compensated
// distribution's lower variance per sample wins (depth 5: up to 1.3x; docs/results.md).
ETK_FN ETK_GLOBAL const float* etk_light_dist(EtkScene S, EtkParams p, int depth) {
    return (p.strategy == ETK_STRATEGY_COMPENSATED || p.strategy == ETK_STRATEGY_COSINE) &&
                   depth > 0
               ? S.env_dist_comp
               : S.env_dist;
}

// The cosine strategy's bin for a vertex at `depth` with shading normal ns (normal_bins.h): the
// table its light sample is drawn from at a path's first vertex; -1, the full map, below it
// (etk_light_dist: the compensated distribution) and at a dielectric, lit from both sides.
ETK_FN int etk_cosine_cell(EtkMaterial m, float3 ns, int depth) {
    return depth == 0 && !etk_bsdf_is_dielectric(m) ? etk_normal_bin(ns) : -1;
}

// The compensated (and cosine) strategy's BSDF sample at a path's last vertex, where the map's
// light sits in a few blocks on black (a studio's lamps, spot1Lux): taken only with probability q,
// the expected BSDF sample count, and weighted by MIS on the counts (1 p_light, q p_bsdf): the
// light sample counts f L cos / (p_light + q p_bsdf) (balance), a BSDF sample, when taken, the same
// over (p_light + q p_bsdf) -- unbiased for every q in (0, 1], and never above the light sample's
// own value, so a rare BSDF sample makes no firefly. Most of those BSDF samples would look at black
// (their rays are not traced there, but drawing and mapping them is a quarter of a depth-1 render
// of spot1Lux) and the light sample finds the lamps alone: q is the most the BSDF's samples can
// put into the directions that are not black for certain, p_bsdf's bound over them times their
// solid angle (lit_sr), so a lobe that could put more of its samples there -- a glossy one facing
// a lamp -- keeps them. 1 for a map without a black block (bit for bit the strategy without it),
// at delta vertices, below the last bounce and for the other strategies; 0 where the BSDF
// reflects nothing at all.
ETK_FN float etk_last_bsdf_share(EtkParams p, EtkMaterial m, float3 wo, int last, int delta) {
    if ((p.strategy != ETK_STRATEGY_COMPENSATED && p.strategy != ETK_STRATEGY_COSINE) || !last ||
        delta || p.env.black_w == 0)
        return 1.0f;
    return fmin(1.0f, p.env.lit_sr * etk_bsdf_pdf_bound(m, wo));
}
// The uniform number that chooses whether that sample is taken: a hash of seed, pixel and sample,
// independent of the vertex's Sobol' points (whose pairs cost ~115 instructions a sample under
// valgrind; these three hashes ~20). Only a path's last vertex asks, one a sample, so the depth
// need not be in it.
ETK_FN float etk_last_bsdf_choice(EtkParams p, int pixel) {
    uint key = etk_hash_combine(p.seed ^ 0x2c1b3c6du, (uint)pixel);
    return etk_unit_float(etk_hash(key + p.sample_index * 0x9e3779b9u));
}

// Adaptive allocation (ETK_STRATEGY_ADAPTIVE). A vertex draws two samples -- A, traced as the
// shadow ray, and B, the continuation -- each from the light distribution or the BSDF, so that
// s of the two are light samples in expectation: A is a light sample with probability min(s, 1),
// B with probability max(s - 1, 0) (s <= 1 below the last bounce, where B must be a BSDF
// sample to carry the path on). With expected counts n_light = s, n_bsdf = 2 - s, a sample
// drawn by technique t counts f cos L w_t / (n_t p_t) for weights w_t that sum to one:
// unbiased for every s, as long as the BSDF keeps a share (s < 2) where the compensated
// distribution is zero. The weights are the MIS heuristic's on n_t p_t (balance: the sample
// counts f cos L / (s p_light + (2 - s) p_bsdf)); s = 1 is exactly the compensated strategy,
// one sample of each. Each material bin also picks the light distribution (full or
// compensated) and the GGX sampling (ETK_BIN_*); the host learns all three per bin from the
// first passes (host/lib/render/light_share.h). Returns s; *flags: the bin's ETK_BIN_*.
ETK_FN float etk_vertex_config(EtkScene S, EtkParams p, int prim, int pixel, int last, int* flags) {
    float s;
    if (p.learn) {
        int k = etk_learning_candidate(p.seed, pixel);
        s = etk_learning_share(k, last);
        *flags = etk_learning_flags(k);
    } else {
        int bin = S.material_bin[S.tri_material[prim]];
        s = p.light_share[bin];
        *flags = p.bin_flags[bin];
    }
    return last ? s : fmin(s, 1.0f);
}
// The continuation's record of its vertex for etk_escaped (beta.w): the share, +4 if it
// is a light sample, +8 if the vertex sampled the compensated distribution.
ETK_FN float etk_share_code(float s, int from_light, int flags) {
    return s + (from_light ? 4.0f : 0.0f) + ((flags & ETK_BIN_COMPENSATED) ? 8.0f : 0.0f);
}
// w_t / (n_t p_t) of a sample drawn by the light (from_light) or the BSDF at share s.
ETK_FN float etk_share_weight(int heuristic, float s, float pl, float pb, int from_light) {
    float a = s * pl, b = (2.0f - s) * pb;
    if (heuristic == ETK_HEURISTIC_POWER) {
        float d = a * a + b * b;
        return d > 0.0f ? (from_light ? a : b) / d : 0.0f;
    }
    return a + b > 0.0f ? 1.0f / (a + b) : 0.0f;
}
// The density continuation B was drawn from at a vertex of share s.
ETK_FN float etk_share_continuation_density(float s, float pl, float pb) {
    float cb = fmax(s - 1.0f, 0.0f);
    return cb * pl + (1.0f - cb) * pb;
}

// The surface a path's ray hit (its hit record, stored by the intersect stage).
ETK_FN EtkSurface etk_path_surface(EtkScene S, EtkPaths P, EtkParams p, int slot) {
    float4 h4 = P.hit[slot];
    EtkHit h;
    h.t = h4.x;
    h.prim = (int)as_uint(h4.y);
    h.b1 = h4.z;
    h.b2 = h4.w;
    return etk_surface_at(S, p, etk_xyz(P.ray_o[slot]), etk_xyz(P.ray_d[slot]), h);
}

// Splitting (the mis strategy with p.light_samples = nl, p.bsdf_samples = nb, as in a branched
// path tracer): a non-delta vertex takes nl light and nb BSDF samples, each weighted by
// etk_light_sample_weight / etk_bsdf_sample_weight.
// Sample 0 of each is the usual shadow ray and continuation (weighted in etk_shade and
// etk_escaped); samples 1 .. n - 1, returned here as their sum over beta, count only the map's
// light they see, their visibility traced at once (as a light set's, etk_shade_lights). Each
// technique's n points are its sample point shifted by a rank-1 lattice (etk_lattice_point), so
// they stratify the vertex's square; the BSDF's lobe choice is stratified the same way. With
// nl = nb = 1 nothing here runs and the weights are the paper's, bit for bit. *traced: the rays
// traced.
ETK_FN float3 etk_split_samples(EtkScene S, EtkParams p, EtkSurface s, EtkMaterial m, float3 t,
                                float3 b, float3 ns, int pixel, uint pair, uint* traced) {
    float3 sum = make_float3(0.0f, 0.0f, 0.0f), wo = s.wo, ng = s.ng;
    uint nl = (uint)p.light_samples, nb = (uint)p.bsdf_samples;
    ETK_GLOBAL const float* dist = etk_light_dist(S, p, 0); // mis only: the full distribution
    float2 u = etk_dims(p, pixel, pair);
    for (uint j = 1u; j < nl; ++j) {
        EtkEnvSample ls = etk_env_sample(dist, p.env, etk_lattice_point(u, j, nl));
        float3 wi = etk_to_local(ls.dir, t, b, ns);
        if (!(ls.pdf > 0.0f) || !etk_light_side_ok(m, wi.z, dot(ls.dir, ng)))
            continue;
        float w = etk_light_sample_weight(p, 1.0f, ls.pdf, etk_bsdf_pdf(m, wo, wi));
        float3 c = etk_bsdf_eval(m, wo, wi) * etk_env_radiance_uv(S.env_texels, p.env, ls.uv) *
                   (fabs(wi.z) * w / ls.pdf);
        if (!(etk_max3(c) > 0.0f))
            continue;
        ++*traced;
        if (etk_dl_visible(S, s, ls.dir))
            sum += c;
    }
    float2 ub = etk_dims(p, pixel, pair + 1u);
    float lobe0 = etk_dims(p, pixel, pair + 2u).x;
    float inv_nb = etk_inv_pow2(nb);
    for (uint j = 1u; j < nb; ++j) {
        float lobe = lobe0 + (float)j * inv_nb;
        EtkBsdfSample bs =
            etk_bsdf_sample(m, wo, etk_lattice_point(ub, j, nb), lobe >= 1.0f ? lobe - 1.0f : lobe);
        if (!(bs.pdf > 0.0f) || bs.delta)
            continue;
        float3 wi_world = etk_from_local(bs.wi, t, b, ns);
        if (!etk_same_side(bs.wi.z, dot(wi_world, ng)))
            continue; // as the continuation: across the geometric surface, it would leak light
        float2 uv = etk_env_uv(p.env, wi_world);
        float w = etk_bsdf_sample_weight(p, 1.0f, bs.pdf, etk_env_pdf_uv(dist, p.env, uv));
        float3 c = bs.weight * etk_env_radiance_uv(S.env_texels, p.env, uv) * w;
        if (!(etk_max3(c) > 0.0f))
            continue;
        ++*traced;
        if (etk_dl_visible(S, s, wi_world))
            sum += c;
    }
    return sum;
}

// Stage 1: a camera ray for slot i.
ETK_FN void etk_generate(ETK_STAGE_PARAMS) {
    (void)out;
    (void)S;
    (void)F;
    int pixel = p.first_pixel + i;
    float3 d = etk_camera_dir(p, pixel);
    P.ray_o[i] = etk_f4(etk_p3(p.eye), 0.0f);
    P.ray_d[i] = etk_f4(d, -1.0f);
    P.beta[i] = make_float4(1.0f, 1.0f, 1.0f, 0.0f);
    // w: the path's eta scale for Russian roulette (the continuation's, below), 1 to start.
    P.radiance[i] = make_float4(0.0f, 0.0f, 0.0f, 1.0f);
    P.pixel[i] = pixel;
    if (p.learn) // no bin unless the camera ray hits a non-delta surface
        P.learn_bin[i] = -1;
    Q.ray_out[i] = i;
}

// A ray that left the scene sees the environment, weighted against light sampling.
ETK_FN void etk_escaped(EtkScene S, EtkPaths P, EtkParams p, int slot) {
    float4 d = P.ray_d[slot];
    float2 uv = etk_env_uv(p.env, etk_xyz(d));
    float w = 1.0f;
    if (d.w >= 0.0f) { // a non-delta continuation; d.w: the density it was drawn from (the
                       // BSDF's, or a guided vertex's mixture: the MIS weight needs that one)
        if (p.strategy == ETK_STRATEGY_ADAPTIVE) { // d.w: p_bsdf of the direction (etk_shade)
            float s = P.beta[slot].w;
            int comp = s >= 8.0f;
            s = comp ? s - 8.0f : s;
            int from_light = s >= 4.0f;
            s = from_light ? s - 4.0f : s;
            float pl = etk_env_pdf_uv(comp ? S.env_dist_comp : S.env_dist, p.env, uv);
            w = etk_share_continuation_density(s, pl, d.w) *
                etk_share_weight(p.heuristic, s, pl, d.w, from_light);
        } else if (etk_strategy_is_mis(p.strategy)) {
            // The visibility strategy's density: from the vertex's grid cell (beta.w) and, for
            // the portal table, the continuation's origin (portal_guide.h); the cell's light
            // samples are the weight's count.
            // The cosine strategy's: the vertex's normal bin (beta.w; -1: the full map).
            int guided = p.strategy == ETK_STRATEGY_VISIBILITY, cell = (int)P.beta[slot].w;
            float pl = guided
                           ? etk_guide_light_pdf(S, p, cell, etk_xyz(P.ray_o[slot]), etk_xyz(d), uv)
                           : etk_env_pdf_uv(etk_light_dist(S, p, (int)P.ray_o[slot].w - 1), p.env,
                                            uv); // the continuation's vertex
            if (p.strategy == ETK_STRATEGY_COSINE && cell >= 0)
                pl *= etk_guide_factor(S, p, cell, uv);
            float lc = guided ? etk_guide_light_count(S, p, cell) : 1.0f;
            w = etk_bsdf_sample_weight(p, lc, d.w, pl); // sample 0 of the vertex's BSDF samples
        } else if (p.strategy != ETK_STRATEGY_BSDF)
            w = 0.0f; // light sampling alone accounts for this direction
    }
    if (w > 0.0f) {
        float3 L = etk_env_radiance_uv(S.env_texels, p.env, uv) * w;
        float4 r = P.radiance[slot];
        P.radiance[slot] = etk_f4(etk_xyz(r) + etk_xyz(P.beta[slot]) * L, r.w);
    }
}

// Stage 2: closest hit, queued for shading; a ray that escaped takes the environment's light here
// and then, rather than through a queue and a stage of its own (issue 12: one launch and one
// queue push fewer per bounce).
ETK_FN void etk_intersect(ETK_STAGE_PARAMS) {
    (void)F;
    int slot = Q.ray_in[i];
    float4 o = P.ray_o[slot], d = P.ray_d[slot];
    EtkHit h;
    // A ray from the last vertex ends wherever it hits: whether it hits anything is all that
    // matters, which any-hit traversal answers sooner (the same triangle tests, so the same
    // answer).
    int ends = (int)o.w >= p.max_depth;
    if (!etk_bvh_traverse(S.nodes, S.packets, etk_xyz(o), etk_xyz(d), 3.0e38f, ends, &h)) {
        etk_escaped(S, P, p, slot);
        return;
    }
    if (ends)
        return; // the path ends here: no more bounces allowed
    P.hit[slot] = make_float4(h.t, as_float((uint)h.prim), h.b1, h.b2);
    out->slot[ETK_Q_SHADE] = slot;
}

// Stage 2': the shade queue's light samples, drawn ahead of the shade stage ETK_LIGHT_BATCH at a
// time (etk_env_sample_batch_uv / _dir, etk_env_radiance_batch: the cache misses of a batch
// overlap, where one sample per shade
// call leaves them in series) for the strategies whose light sample is one map sample
// (etk_batches_light_samples). i: the batch; the queue's length is the shade counter intersect
// left (the host launches this stage after it). A batch past the queue's end repeats its last
// entry and stores nothing for the repeats. The same values as etk_env_sample in the shade stage
// would draw: the same bits.
ETK_FN void etk_sample_lights(ETK_STAGE_PARAMS) {
    (void)out;
    (void)F;
    int n = (int)Q.counters[ETK_Q_SHADE], first = i * ETK_LIGHT_BATCH;
    // Every path of a shade queue is at the same depth (run_wave shades one bounce at a time).
    int depth = (int)P.ray_o[Q.shade[min(first, n - 1)]].w;
    float xu[ETK_LIGHT_BATCH], xv[ETK_LIGHT_BATCH];
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k) {
        int slot = Q.shade[min(first + k, n - 1)];
        float2 xi = etk_dims(p, P.pixel[slot], etk_vertex_pair((int)P.ray_o[slot].w));
        xu[k] = xi.x;
        xv[k] = xi.y;
    }
    if (p.strategy == ETK_STRATEGY_COSINE && depth == 0) {
        // Each from its vertex's bin's table (etk_guide_sample's steps, each over the batch, so
        // that the cache misses of the bins' tables and the map's rows overlap), the bin kept in
        // light_L.w for the shade stage.
        int cell[ETK_LIGHT_BATCH], R[ETK_LIGHT_BATCH];
        float2 t[ETK_LIGHT_BATCH], uv[ETK_LIGHT_BATCH];
        int m = min(ETK_LIGHT_BATCH, n - first);
        for (int k = 0; k < m; ++k) {
            int slot = Q.shade[first + k];
            float4 h = P.hit[slot];
            int prim = (int)as_uint(h.y), front;
            float3 ng;
            float3 ns = etk_shading_normal(S, prim, h.z, h.w, etk_xyz(P.ray_d[slot]), &ng, &front);
            cell[k] =
                p.guide_ready
                    ? etk_cosine_cell(etk_material_load(S.materials, S.tri_material[prim]), ns, 0)
                    : -1;
        }
        for (int k = 0; k < m; ++k)
            R[k] = cell[k] >= 0
                       ? etk_guide_pick_region(S.guide_cells + cell[k] * ETK_GUIDE_CELL_FLOATS,
                                               make_float2(xu[k], xv[k]), &t[k])
                       : 0;
        for (int k = 0; k < m; ++k)
            uv[k] = cell[k] >= 0 ? etk_guide_sample_region(S, p.env, R[k], t[k])
                                 : make_float2(0.0f, 0.0f);
        for (int k = 0; k < m; ++k) {
            EtkEnvSample ls = cell[k] >= 0
                                  ? etk_guide_sample_at(S, p, cell[k], uv[k])
                                  : etk_env_sample(S.env_dist, p.env, make_float2(xu[k], xv[k]));
            uv[k] = ls.pdf > 0.0f ? ls.uv : make_float2(-1.0f, -1.0f);
            P.light_dir[Q.shade[first + k]] = etk_f4(ls.dir, ls.pdf);
        }
        for (int k = 0; k < m; ++k) // the texels, last: a loop of lookups alone
            P.light_L[Q.shade[first + k]] =
                etk_f4(uv[k].x >= 0.0f ? etk_env_radiance_uv(S.env_texels, p.env, uv[k])
                                       : make_float3(0.0f, 0.0f, 0.0f),
                       (float)cell[k]);
        return;
    }
    float dx[ETK_LIGHT_BATCH], dy[ETK_LIGHT_BATCH], dz[ETK_LIGHT_BATCH], pdf[ETK_LIGHT_BATCH];
    float Lr[ETK_LIGHT_BATCH], Lg[ETK_LIGHT_BATCH], Lb[ETK_LIGHT_BATCH];
    int row[ETK_LIGHT_BATCH], col[ETK_LIGHT_BATCH];
    etk_env_light_batch(etk_light_dist(S, p, depth), S.env_texels, p.env, xu, xv, dx, dy, dz, pdf,
                        Lr, Lg, Lb, row, col);
    for (int k = 0; k < ETK_LIGHT_BATCH && first + k < n; ++k) {
        int slot = Q.shade[first + k];
        P.light_dir[slot] = make_float4(dx[k], dy[k], dz[k], pdf[k]);
        P.light_L[slot] = make_float4(Lr[k], Lg[k], Lb[k], 0.0f);
    }
}

// The light sample sample_lights drew for the path in `slot`: direction and density (its radiance,
// drawn too, is light_L; its map coordinates are not kept, nothing of these strategies reads them
// in the shade stage).
ETK_FN EtkEnvSample etk_drawn_light_sample(EtkPaths P, int slot) {
    float4 d = P.light_dir[slot];
    EtkEnvSample s;
    s.dir = etk_xyz(d);
    s.pdf = d.w;
    s.uv = make_float2(0.0f, 0.0f); // not needed: its radiance is drawn too (light_L)
    s.row = 0;
    s.col = 0;
    return s;
}

// Stage 3: at a surface: one light sample (pushed as a shadow ray) and one BSDF sample (pushed as
// the continuation ray); for the adaptive strategy, samples A and B chosen by the vertex's share.
// Forced inline: PoCL otherwise keeps the stage a call per work-item, which copies the scene,
// path, queue, film and parameter structs (about a kilobyte, passed by value) on every call;
// inlined, its shade stage takes 5-9% less time (bunny_esplanade, depth 1 and 5) for a cold
// program build 4 s longer. GCC's native code is the same speed either way.
ETK_FORCE_INLINE_FN void etk_shade(ETK_STAGE_PARAMS) {
    int slot = Q.shade[i];
    int depth = (int)P.ray_o[slot].w;
    int pixel = P.pixel[slot];
    EtkSurface s = etk_path_surface(S, P, p, slot);
    if (depth == 0) // the camera ray's hit: the AOVs
        etk_aov_first_hit(F, p, pixel, s, etk_xyz(P.ray_d[slot]), P.hit[slot].x);
    float3 t = s.t, b = s.b, ns = s.ns, ng = s.ng, wo = s.wo;
    EtkMaterial m = s.m;
    float3 beta = etk_xyz(P.beta[slot]);
    uint pair = etk_vertex_pair(depth);
    int last = etk_last_bounce(p, depth);
    int adaptive = p.strategy == ETK_STRATEGY_ADAPTIVE;
    int delta = etk_bsdf_is_delta(m);
    float bq = etk_last_bsdf_share(p, m, wo, last, delta); // the BSDF sample's expected count
    // Adaptive: this vertex's share, distribution and GGX sampling; learning passes note the
    // first hit's bin.
    float share = 1.0f;
    int flags = 0;
    ETK_GLOBAL const float* dist = etk_light_dist(S, p, depth);
    if (adaptive && !delta) {
        int prim = (int)as_uint(P.hit[slot].y);
        share = etk_vertex_config(S, p, prim, pixel, last, &flags);
        dist = (flags & ETK_BIN_COMPENSATED) ? S.env_dist_comp : S.env_dist;
        m.ggx_sampling = (flags & ETK_BIN_VNDF) ? ETK_GGX_VNDF : ETK_GGX_NDF;
        if (p.learn && depth == 0)
            P.learn_bin[slot] = S.material_bin[S.tri_material[prim]];
    }
    int guided = p.strategy == ETK_STRATEGY_VISIBILITY;
    // The cosine strategy's normal bin (-1: the full map), as sample_lights found it if it drew
    // the light sample.
    int cell = guided                              ? etk_guide_cell(p, s.origin, ng)
               : p.strategy != ETK_STRATEGY_COSINE ? 0
               : p.light_batch && depth == 0       ? (int)P.light_L[slot].w
                                                   : etk_cosine_cell(m, ns, depth);
    int binned = p.strategy == ETK_STRATEGY_COSINE && cell >= 0;
    // The guided share of the continuation; none at the last bounce, where the continuation
    // only gathers the map's light, which the light sample already draws from a learned table.
    float cg = guided && !last ? etk_cguide_share(S, p, cell, m) : 0.0f;

    // The visibility strategy's expected light samples at this vertex (etk_guide_light_count):
    // below 1 the light sample is taken with that probability, on a sample dimension of its own.
    float lc = guided ? etk_guide_light_count(S, p, cell) : 1.0f;
    int take_light = !(lc < 1.0f) || etk_dims(p, pixel, ETK_PAIR_SHARE + (uint)depth).x < lc;

    // Light sample (sample A of the adaptive strategy).
    if (p.strategy != ETK_STRATEGY_BSDF && !delta && take_light) {
        // With the sample_lights stage the sample is drawn already, from this pair.
        int drawn = p.light_batch;
        float2 u = drawn ? make_float2(0.0f, 0.0f) : etk_dims(p, pixel, pair);
        float3 c = make_float3(0.0f, 0.0f, 0.0f);
        float3 wi_world;
        float learn_val = 0.0f;
        int learn_key = 0;
        float2 parts = make_float2(0.0f, 0.0f); // visibility: p_vis and p_portal of the sample
        if (p.strategy == ETK_STRATEGY_SIS) {
            // One stratum per sample, every stratum once in each run of light_count samples,
            // weighted by light_count x its power.
            int k = (int)(p.sample_index % (uint)p.light_count);
            float3 md =
                etk_dl_stratum_direction(S.strata_texels, S.strata_cdf, S.strata_begin[k],
                                         S.strata_begin[k + 1], p.strata_width, p.strata_height, u);
            wi_world = normalize(etk_env_to_world(p.env, md));
            float3 E = etk_xyz(S.lights[2 * k + 1]) * (float)p.light_count;
            c = beta * etk_dl_unshadowed(s, wi_world, E);
        } else if (adaptive) {
            // One pair of technique choices per vertex: (A's technique, A's BSDF lobe) when
            // share < 1 (B is then a BSDF sample), (B's technique, -) when share > 1 (A is then
            // a light sample); share = 1 needs neither.
            float2 sel = share < 1.0f ? etk_dims(p, pixel, ETK_PAIR_SHARE + (uint)depth)
                                      : make_float2(0.0f, 0.0f);
            float2 light_uv;
            float pl = 0.0f;
            int ok, from_light = sel.x < fmin(share, 1.0f);
            if (from_light) {
                EtkEnvSample ls = etk_env_sample(dist, p.env, u);
                wi_world = ls.dir;
                light_uv = ls.uv;
                pl = ls.pdf;
                ok = ls.pdf > 0.0f;
            } else {
                EtkBsdfSample bs = etk_bsdf_sample(m, wo, u, sel.y);
                wi_world = etk_from_local(bs.wi, t, b, ns);
                light_uv = etk_env_uv(p.env, wi_world);
                pl = etk_env_pdf_uv(dist, p.env, light_uv);
                ok = bs.pdf > 0.0f;
            }
            float3 wi = etk_to_local(wi_world, t, b, ns);
            if (ok && etk_light_side_ok(m, wi.z, dot(wi_world, ng))) {
                float pb = etk_bsdf_pdf(m, wo, wi);
                float wq = etk_share_weight(p.heuristic, share, pl, pb, from_light);
                if (wq > 0.0f)
                    c = beta * etk_bsdf_eval(m, wo, wi) *
                        etk_env_radiance_uv(S.env_texels, p.env, light_uv) * (fabs(wi.z) * wq);
            }
        } else {
            float2 light_uv; // map coordinates of the light direction
            float pdf_light;
            if (p.strategy == ETK_STRATEGY_UNIFORM) {
                wi_world = etk_sample_uniform_sphere(u);
                light_uv = etk_env_uv(p.env, wi_world);
                pdf_light = 0.25f * ETK_INV_PI;
            } else {
                EtkEnvSample ls = guided   ? etk_guide_light_sample(S, p, cell, s, u, &parts)
                                  : drawn  ? etk_drawn_light_sample(P, slot)
                                  : binned ? etk_guide_sample(S, p, cell, u)
                                           : etk_env_sample(dist, p.env, u);
                wi_world = ls.dir;
                light_uv = ls.uv;
                pdf_light = ls.pdf;
            }
            float3 wi = etk_to_local(wi_world, t, b, ns);
            // Above the surface, or below it at a dielectric (it transmits light from there).
            if (pdf_light > 0.0f && etk_light_side_ok(m, wi.z, dot(wi_world, ng))) {
                float3 f = etk_bsdf_eval(m, wo, wi);
                float w = 1.0f; // sample 0 of the vertex's light samples
                if (etk_strategy_is_mis(p.strategy)) {
                    // The continuation's density: the BSDF's, at a guided vertex its mixture with
                    // the learned directions (asked only there: the call's arguments cost ~65
                    // instructions a light sample in GCC's native code even when it returns at
                    // once).
                    float pb = bq * etk_bsdf_pdf(m, wo, wi);
                    if (cg > 0.0f)
                        pb = etk_cguide_mix_pdf(S, p, cell, cg, pb, etk_surface_origin(s, wi_world),
                                                wi_world);
                    w = etk_light_sample_weight(p, lc, pdf_light, pb);
                }
                float3 L = drawn ? etk_xyz(P.light_L[slot])
                                 : etk_env_radiance_uv(S.env_texels, p.env, light_uv);
                c = beta * f * L * (fabs(wi.z) * w / pdf_light);
                // Visibility learning: what this direction would bring, unweighted, and where.
                learn_val = etk_luma(L) * fabs(wi.z) / pdf_light;
                learn_key = cell * ETK_GUIDE_REGIONS + etk_guide_region(p.env, light_uv);
            }
        }
        if (etk_max3(c) > 0.0f) {
            // Shadow rays stop at any surface, glass included: light through glass (caustics)
            // is the continuation's to find, as indirect light, never the light sample's.
            // The key as a float value (exact below 2^24), never an int's bits: o.w rides along
            // in the origin's fourth lane through the traversal (params.h).
            P.shadow_o[slot] = etk_f4(etk_surface_origin(s, wi_world), (float)learn_key);
            P.shadow_d[slot] = etk_f4(wi_world, 3.0e38f);
            P.shadow_L[slot] = etk_f4(c, learn_val);
            if (p.guide_learn)
                P.guide_parts[slot] = parts;
            out->slot[ETK_Q_SHADOW] = slot;
        }
    }

    if (p.light_samples * p.bsdf_samples > 1 && !delta) {
        uint traced = 0u;
        float3 e = etk_split_samples(S, p, s, m, t, b, ns, pixel, pair, &traced);
        if (traced > 0u) // counted with the light set's rays (traced in a shade stage too)
            ETK_ATOMIC_ADD(Q.counters + ETK_Q_LIGHT_RAYS, traced);
        if (etk_max3(e) > 0.0f) {
            float4 r = P.radiance[slot];
            P.radiance[slot] = etk_f4(etk_xyz(r) + beta * e, r.w);
        }
    }

    // The continuation (a BSDF sample, or at a guided vertex a sample of the mixture with the
    // learned directions). Not needed when nothing it could reach would count.
    // SIS (like the light set) renders direct lighting from its strata alone: no continuation.
    if (p.strategy == ETK_STRATEGY_SIS || (last && p.strategy != ETK_STRATEGY_BSDF &&
                                           !etk_strategy_is_mis(p.strategy) && !adaptive && !delta))
        return;
    // Taken with probability bq (etk_last_bsdf_share), chosen by a hash of the sample: a Sobol'
    // pair would cost twice as much, and most of these samples are never drawn.
    if (bq < 1.0f && !(etk_last_bsdf_choice(p, pixel) < bq))
        return;
    float2 rr = etk_dims(p, pixel, pair + 2u);
    float2 u = etk_dims(p, pixel, pair + 1u);
    float3 wi_world, weight;
    float pdf; // p_bsdf of the direction for the adaptive strategy; else the pdf it was drawn with
    int delta_sample, b_from_light = 0;
    float rr_scale = 1.0f; // the throughput Russian roulette weighs, relative to beta
    float wz;              // the direction's cosine in the shading frame: < 0 for a transmission
    if (adaptive && !delta && share > 1.0f &&
        etk_dims(p, pixel, ETK_PAIR_SHARE + (uint)depth).x < share - 1.0f) {
        // Continuation B drawn from the light distribution (last bounce, share > 1).
        EtkEnvSample ls = etk_env_sample(dist, p.env, u);
        wi_world = ls.dir;
        float3 wi = etk_to_local(wi_world, t, b, ns);
        pdf = etk_bsdf_pdf(m, wo, wi);
        if (!(ls.pdf > 0.0f) || !(pdf > 0.0f) || wi.z == 0.0f)
            return;
        weight = etk_bsdf_eval(m, wo, wi) *
                 (fabs(wi.z) / etk_share_continuation_density(share, ls.pdf, pdf));
        wz = wi.z;
        delta_sample = 0;
        b_from_light = 1;
    } else if (cg > 0.0f) {
        // A guided vertex: the mixture of the cell's learned directions and the BSDF.
        EtkGuidedSample g = etk_cguide_sample_mixture(S, p, cell, cg, m, s, t, b, ns, u, rr.x);
        if (!(g.pdf > 0.0f) || !(g.pdf_bsdf > 0.0f))
            return; // below the surface: nothing a diffuse surface reflects
        wi_world = g.wi_world;
        pdf = g.pdf;
        weight = etk_bsdf_eval(m, wo, g.wi) * (g.wi.z / pdf);
        wz = g.wi.z;
        delta_sample = 0;
        // Russian roulette as if the BSDF had drawn the direction: a guided sample towards bright
        // light has a small weight (its density is high), and a survival probability that
        // followed it would cut exactly the paths the guide found.
        rr_scale = pdf / g.pdf_bsdf;
    } else {
        EtkBsdfSample bs = etk_bsdf_sample(m, wo, u, rr.x);
        if (!(bs.pdf > 0.0f))
            return;
        wi_world = etk_from_local(bs.wi, t, b, ns);
        wz = bs.wi.z;
        weight = bs.weight;
        pdf = bs.pdf;
        if (bq < 1.0f) { // a sample of expected count bq: density bq p_bsdf in the miss's weight
            weight = weight / bq;
            pdf = pdf * bq;
        }
        delta_sample = bs.delta;
        if (adaptive && !delta && share > 1.0f) { // drawn from the mixture, not the BSDF alone
            float pl = etk_env_pdf_uv(dist, p.env, etk_env_uv(p.env, wi_world));
            weight = weight * (pdf / etk_share_continuation_density(share, pl, pdf));
        }
    }
    if (!etk_same_side(wz, dot(wi_world, ng)))
        return; // across the geometric surface from its shading side: would leak light
    // The last bounce's continuation can only bring back the map's light (no surface emits):
    // where the map is black for certain in its direction it would bring nothing, and is not
    // traced -- most of them under a map whose light is a few texels (a studio's lamps,
    // spot1Lux). A small mask rather than the texels: their lookup here would cost about what
    // the ray saves (cache misses in a large map). The image is the same to the bit.
    if (last && p.env.black_w > 0 &&
        etk_env_black_uv(S.env_black, p.env, etk_env_uv(p.env, normalize(wi_world))))
        return;
    beta = beta * weight;
    // A refraction scales radiance by 1 / eta^2 (dielectric.h), into glass and back out again:
    // Russian roulette weighs the throughput without it (pbrt's etaScale), or paths inside glass
    // of index 1.5 would survive 1 in 2.25 and come out as fireflies of 2.25x their worth.
    float4 rad = P.radiance[slot];
    if (etk_bsdf_is_dielectric(m) && wz < 0.0f)
        rad.w *= m.eta * m.eta;
    // Russian roulette past the path's first rr_depth surfaces (this vertex is surface depth + 1).
    if (depth >= p.rr_depth) {
        float survive = fmin(0.95f, etk_max3(beta) * rr_scale * rad.w);
        if (!(rr.y < survive))
            return;
        beta = beta / survive;
    }
    if (!(etk_max3(beta) > 0.0f) || !isfinite(etk_max3(beta)))
        return;
    P.ray_o[slot] = etk_f4(etk_surface_origin(s, wi_world), (float)(depth + 1));
    P.ray_d[slot] = etk_f4(normalize(wi_world), delta_sample ? -1.0f : pdf);
    P.beta[slot] = etk_f4(beta, guided || p.strategy == ETK_STRATEGY_COSINE
                                    ? (float)cell
                                    : etk_share_code(share, b_from_light, flags));
    P.radiance[slot] = rad;
    out->slot[ETK_Q_RAY_OUT] = slot;
}

// Stage 4: shadow rays add their contribution when nothing blocks them.
ETK_FN void etk_shadow(ETK_STAGE_PARAMS) {
    (void)out;
    (void)F;
    int slot = Q.shadow[i];
    float4 o = P.shadow_o[slot], d = P.shadow_d[slot];
    EtkHit h;
    int visible = !etk_bvh_traverse(S.nodes, S.packets, etk_xyz(o), etk_xyz(d), d.w, 1, &h);
    if (visible) {
        float4 r = P.radiance[slot];
        P.radiance[slot] = etk_f4(etk_xyz(r) + etk_xyz(P.shadow_L[slot]), r.w);
    }
    if (p.guide_learn) { // the visibility strategy's records, in shadow-queue order (host reads)
        P.guide_key[i] = (int)o.w;
        P.guide_val[i] = visible ? P.shadow_L[slot].w : 0.0f;
        float t; // where an unoccluded ray leaves the scene's box: the portal table's record
        P.guide_exit[i] =
            visible ? etk_portal_exit(etk_portal_table(S, p), etk_xyz(o), etk_xyz(d), &t) : -1;
        P.guide_rec_parts[i] = P.guide_parts[slot];
    }
}

// Stage 3': the shade stage of a directional light set (ETK_STRATEGY_LIGHTS, direct lighting
// only): every light of the set at every hit, one any-hit shadow ray each, summed in light order.
ETK_FN void etk_shade_lights(ETK_STAGE_PARAMS) {
    (void)out;
    int slot = Q.shade[i];
    EtkSurface s = etk_path_surface(S, P, p, slot);
    if ((int)P.ray_o[slot].w == 0) // the camera ray's hit: the AOVs
        etk_aov_first_hit(F, p, P.pixel[slot], s, etk_xyz(P.ray_d[slot]), P.hit[slot].x);
    float3 beta = etk_xyz(P.beta[slot]);
    float3 L = make_float3(0.0f, 0.0f, 0.0f);
    uint traced = 0u;
    for (int k = 0; k < p.light_count; ++k) {
        float3 c = etk_dl_unshadowed(s, etk_xyz(S.lights[2 * k]), etk_xyz(S.lights[2 * k + 1]));
        if (!(etk_max3(c) > 0.0f))
            continue;
        ++traced;
        L += etk_dl_visible(S, s, etk_xyz(S.lights[2 * k])) ? c : make_float3(0.0f, 0.0f, 0.0f);
    }
    if (traced > 0u)
        ETK_ATOMIC_ADD(Q.counters + ETK_Q_LIGHT_RAYS, traced);
    float4 r = P.radiance[slot];
    P.radiance[slot] = etk_f4(etk_xyz(r) + beta * L, r.w);
}

// Stage 5: the pass's path radiance into the film. A non-finite sample counts as zero rather
// than poisoning the pixel, and is counted: the host reports any, and the tests require none.
ETK_FN void etk_accumulate(ETK_STAGE_PARAMS) {
    (void)out;
    (void)S;
    (void)p;
    int pixel = P.pixel[i];
    float3 L = etk_xyz(P.radiance[i]);
    if (!(isfinite(L.x) && isfinite(L.y) && isfinite(L.z))) {
        ETK_ATOMIC_INC(Q.counters + ETK_Q_NONFINITE);
        L = make_float3(0.0f, 0.0f, 0.0f);
    }
    etk_film_add(F, pixel, L);
}

ETK_END

#endif
