// The wavefront path tracer's stages, written once for the OpenCL kernels (wavefront.cl) and the
// native back end. Paths live in structure-of-arrays buffers indexed by slot; work queues are
// arrays of slots whose lengths are counters bumped atomically, so every stage runs over exactly
// the live work. One path per pixel per pass: film accumulation needs no atomics.
//
// Sample dimensions (pairs, regenerated from pixel, sample index, pair; never stored):
//   pair 0: pixel jitter; for bounce d: pair 1+3d light sample, 2+3d BSDF direction (at a
//   guided vertex: u.x also picks the guide or the BSDF, continuation_guide.h),
//   3+3d (BSDF lobe, Russian roulette); the learned technique's choice to take the light sample:
//   ETK_PAIR_SHARE + d (etk_shade_vertex). Split samples (etk_split_samples) come from the same
//   pairs shifted by a lattice. Pairs are hashed, so these need not be contiguous.
//
// A vertex is shaded in steps (etk_shade): the vertex's facts (etk_shade_vertex), its light sample
// (etk_shade_light), split samples (etk_shade_split), its continuation (etk_shade_continue). Where
// light samples come from is the light-sampling module's to say (light_sampling.h); which
// techniques a pass uses are switches in EtkParams, set by the host from a strategy's name.
#ifndef ETK_INTEGRATOR_H
#define ETK_INTEGRATOR_H
#include "aov.h"
#include "bsdf.h"
#include "bvh.h"
#include "compat.h"
#include "continuation_guide.h"
#include "directional_lights.h"
#include "envmap.h"
#include "film_accumulate.h"
#include "light_sampling.h"
#include "params.h"
#include "path_state.h"
#include "portal_guide.h"
#include "sampler.h"
#include "surface.h"
#include "visibility_guide.h"
#include "visibility_record.h"

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

// The BSDF sample at a path's last vertex, where the map's light sits in a few blocks on black (a
// studio's lamps, spot1Lux), with the thin_last_bsdf switch (the compensated and cosine
// strategies): taken only with probability q, the expected BSDF sample count, and weighted by MIS
// on the counts (1 p_light, q p_bsdf): the light sample counts f L cos / (p_light + q p_bsdf)
// (balance), a BSDF sample, when taken, the same over (p_light + q p_bsdf) -- unbiased for every q
// in (0, 1], and never above the light sample's own value, so a rare BSDF sample makes no firefly.
// Most of those BSDF samples would look at black (their rays are not traced there, but drawing
// and mapping them is a quarter of a depth-1 render of spot1Lux) and the light sample finds the
// lamps alone: q is the most the BSDF's samples can put into the directions that are not black
// for certain, p_bsdf's bound over them times their solid angle (lit_sr), so a lobe that could put
// more of its samples there -- a glossy one facing a lamp -- keeps them. 1 for a map without a
// black block (bit for bit the estimator without it), at delta vertices, below the last bounce
// and without the switch; 0 where the BSDF reflects nothing at all.
ETK_FN float etk_last_bsdf_share(EtkParams p, EtkMaterial m, float3 wo, int last, int delta) {
    if (!p.thin_last_bsdf || !last || delta || p.env.black_w == 0)
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

// A vertex being shaded: its surface, throughput and place in the path, and what its samples
// are drawn from. Made once per vertex (etk_shade_vertex); the steps after it only read it.
typedef struct {
    EtkSurface s;
    float3 beta; // the path's throughput up to the vertex
    int slot, pixel, depth;
    uint pair; // the vertex's first sample pair (etk_vertex_pair)
    int last;  // the path's last vertex: its continuation can only escape
    int delta; // a delta BSDF: no light sample, no MIS
    EtkLightSource light;
    float light_count; // expected light samples, in (0, 1] (etk_light_count)
    float bsdf_count;  // expected BSDF samples, in [0, 1] (etk_last_bsdf_share)
    float guided;      // the continuation's share drawn from the learned guide (0: none)
} EtkVertex;

// Splitting (the mis strategy with p.light_samples = nl, p.bsdf_samples = nb, as in a branched
// path tracer): a non-delta vertex takes nl light and nb BSDF samples, each weighted by
// etk_light_sample_weight / etk_bsdf_sample_weight.
// Sample 0 of each is the usual shadow ray and continuation (weighted in etk_shade_light and
// etk_escaped); samples 1 .. n - 1, returned here as their sum over beta, count only the map's
// light they see, their visibility traced at once (as a light set's, etk_shade_lights). Each
// technique's n points are its sample point shifted by a rank-1 lattice (etk_lattice_point), so
// they stratify the vertex's square; the BSDF's lobe choice is stratified the same way. With
// nl = nb = 1 nothing here runs and the weights are the paper's, bit for bit. *traced: the rays
// traced.
ETK_FN float3 etk_split_samples(EtkScene S, EtkParams p, EtkVertex v, uint* traced) {
    EtkSurface s = v.s;
    EtkMaterial m = s.m;
    float3 sum = make_float3(0.0f, 0.0f, 0.0f), wo = s.wo, ng = s.ng;
    uint nl = (uint)p.light_samples, nb = (uint)p.bsdf_samples;
    float2 u = etk_dims(p, v.pixel, v.pair), parts;
    for (uint j = 1u; j < nl; ++j) {
        EtkEnvSample ls = etk_light_sample(S, p, v.light, s, etk_lattice_point(u, j, nl), &parts);
        float3 wi = etk_to_local(ls.dir, s.t, s.b, s.ns);
        if (!(ls.pdf > 0.0f) || !etk_light_side_ok(m, wi.z, dot(ls.dir, ng)))
            continue;
        float w = etk_light_sample_weight(p, 1.0f, ls.pdf, etk_bsdf_pdf(m, wo, wi));
        float3 c =
            etk_bsdf_eval(m, wo, wi) * etk_light_radiance(S, p, ls.uv) * (fabs(wi.z) * w / ls.pdf);
        if (!(etk_max3(c) > 0.0f))
            continue;
        ++*traced;
        if (etk_dl_visible(S, s, ls.dir))
            sum += c;
    }
    float2 ub = etk_dims(p, v.pixel, v.pair + 1u);
    float lobe0 = etk_dims(p, v.pixel, v.pair + 2u).x;
    float inv_nb = etk_inv_pow2(nb);
    for (uint j = 1u; j < nb; ++j) {
        float lobe = lobe0 + (float)j * inv_nb;
        EtkBsdfSample bs =
            etk_bsdf_sample(m, wo, etk_lattice_point(ub, j, nb), lobe >= 1.0f ? lobe - 1.0f : lobe);
        if (!(bs.pdf > 0.0f) || bs.delta)
            continue;
        float3 wi_world = etk_from_local(bs.wi, s.t, s.b, s.ns);
        if (!etk_same_side(bs.wi.z, dot(wi_world, ng)))
            continue; // as the continuation: across the geometric surface, it would leak light
        float2 uv = etk_env_uv(p.env, wi_world);
        float pl = etk_light_pdf(S, p, v.light, etk_surface_origin(s, wi_world), wi_world, uv);
        float w = etk_bsdf_sample_weight(p, 1.0f, bs.pdf, pl);
        float3 c = bs.weight * etk_light_radiance(S, p, uv) * w;
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
    int pixel = p.first_pixel + i * p.pixel_stride;
    float3 d = etk_camera_dir(p, pixel);
    P.ray_o[i] = etk_f4(etk_p3(p.eye), 0.0f);
    P.ray_d[i] = etk_f4(d, 0.0f);
    P.depth[i] = 0;
    P.ray_pdf[i] = -1.0f;
    P.ray_cell[i] = 0;
    P.beta[i] = make_float4(1.0f, 1.0f, 1.0f, 0.0f);
    P.radiance[i] = make_float4(0.0f, 0.0f, 0.0f, 0.0f);
    P.eta_scale[i] = 1.0f; // the continuation's (etk_roulette), 1 to start
    P.pixel[i] = pixel;
    P.guide_noted[i] = 0; // no continuation record yet (visibility_record.h)
    Q.ray_out[i] = i;
}

// The weight of a ray that left the scene: a non-delta continuation is weighted against the light
// sample of the vertex that drew it (sample 0 of its BSDF samples), or counts not at all where
// that vertex's light sample alone accounts for the map's light; camera rays and delta samples
// count in full.
ETK_FN float etk_escaped_weight(EtkScene S, EtkPaths P, EtkParams p, int slot, float3 d,
                                float2 uv) {
    float pdf = P.ray_pdf[slot];
    if (!(pdf >= 0.0f))
        return 1.0f;
    int depth = P.depth[slot] - 1; // the vertex that drew the ray
    EtkLightSource src = etk_light_source(p, depth, P.ray_cell[slot]);
    if (!p.mis)
        return src.kind == ETK_LIGHT_NONE ? 1.0f : 0.0f;
    float pl = etk_light_pdf(S, p, src, etk_xyz(P.ray_o[slot]), d, uv);
    return etk_bsdf_sample_weight(p, etk_light_count(S, p, src), pdf, pl);
}

// A ray that left the scene sees the environment, weighted against light sampling.
ETK_FN void etk_escaped(EtkScene S, EtkPaths P, EtkParams p, int slot) {
    float3 d = etk_xyz(P.ray_d[slot]);
    float2 uv = etk_env_uv(p.env, d);
    float w = etk_escaped_weight(S, P, p, slot, d, uv);
    if (w > 0.0f) {
        float3 L = etk_light_radiance(S, p, uv) * w;
        float4 r = P.radiance[slot];
        P.radiance[slot] = etk_f4(etk_xyz(r) + etk_xyz(P.beta[slot]) * L, r.w);
    }
}

// Stage 2: closest hit, queued for shading; a ray that escaped takes the environment's light here
// and then, rather than through a queue and a stage of its own (one launch and one queue push
// fewer per bounce).
ETK_FN void etk_intersect(ETK_STAGE_PARAMS) {
    (void)F;
    int slot = Q.ray_in[i];
    float4 o = P.ray_o[slot], d = P.ray_d[slot];
    EtkHit h;
    // A ray from the last vertex ends wherever it hits: whether it hits anything is all that
    // matters, which any-hit traversal answers sooner (the same triangle tests, so the same
    // answer).
    int ends = P.depth[slot] >= p.max_depth;
    // A guided vertex's continuation, after the vertex's shadow ray: what its record needs (the
    // last vertex's continuation is never guided, and teaches the guide nothing).
    if (p.guide_learn && p.guide_continuation && P.ray_pdf[slot] > 0.0f && !ends)
        etk_guide_note_vertex(P, slot, P.depth[slot] - 1);
    if (!etk_bvh_traverse(S.nodes, S.packets, etk_xyz(o), etk_xyz(d), ETK_RAY_UNBOUNDED, ends,
                          &h)) {
        etk_escaped(S, P, p, slot);
        return;
    }
    if (ends)
        return; // the path ends here: no more bounces allowed
    P.hit[slot] = make_float4(h.t, as_float((uint)h.prim), h.b1, h.b2);
    out->slot[ETK_Q_SHADE] = slot;
}

// The cell (etk_light_cell) of the binned technique's vertex in `slot`, from the hit alone (the
// shade stage finds the same from its surface): sample_lights draws before the surface is made.
ETK_FN int etk_hit_cosine_cell(EtkScene S, EtkPaths P, EtkParams p, int slot) {
    EtkHit h = etk_path_hit(P, slot);
    int front;
    float3 ng;
    float3 ns = etk_shading_normal(S, h.prim, h.b1, h.b2, etk_xyz(P.ray_d[slot]), &ng, &front);
    return etk_cosine_cell(p, etk_material_load(S.materials, S.tri_material[h.prim]), ns);
}

// The sample_lights stage's work-items for a shade queue of `shade` entries: one per batch of
// ETK_LIGHT_BATCH, the last one partly past the queue's end.
ETK_FN int etk_light_batch_items(uint shade) {
    return (int)((shade + (uint)(ETK_LIGHT_BATCH - 1)) / (uint)ETK_LIGHT_BATCH);
}

// Stage 2': the shade queue's light samples, drawn ahead of the shade stage ETK_LIGHT_BATCH at a
// time (etk_env_light_batch, etk_cosine_light_batch, etk_guide_light_batch: the cache misses of
// a batch overlap, where one sample per shade call leaves them in series), where the techniques
// allow it (etk_light_batches). i: the batch; the queue's length is the shade counter intersect
// left (the host launches this stage after it). A batch past the queue's end repeats its last entry
// and stores nothing for the repeats. The same values as etk_light_sample in the shade stage would
// draw: the same bits.
ETK_FN void etk_sample_lights(ETK_STAGE_PARAMS) {
    (void)out;
    (void)F;
    int n = (int)Q.counters[ETK_Q_SHADE], first = i * ETK_LIGHT_BATCH;
    // Every path of a shade queue is at the same depth (run_wave shades one bounce at a time).
    int kind = etk_light_kind(p, P.depth[Q.shade[min(first, n - 1)]]);
    float xu[ETK_LIGHT_BATCH], xv[ETK_LIGHT_BATCH];
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k) {
        int slot = Q.shade[min(first + k, n - 1)];
        float2 xi = etk_dims(p, P.pixel[slot], etk_vertex_pair(P.depth[slot]));
        xu[k] = xi.x;
        xv[k] = xi.y;
    }
    if (kind == ETK_LIGHT_LEARNED) {
        etk_guide_light_batch(S, P, p, Q.shade + first, xu, xv, min(ETK_LIGHT_BATCH, n - first));
        return;
    }
    if (kind == ETK_LIGHT_BINNED) {
        int cell[ETK_LIGHT_BATCH];
        int m = min(ETK_LIGHT_BATCH, n - first);
        for (int k = 0; k < m; ++k)
            cell[k] = p.guide_ready ? etk_hit_cosine_cell(S, P, p, Q.shade[first + k]) : -1;
        etk_cosine_light_batch(S, P, p, Q.shade + first, cell, xu, xv, m);
        return;
    }
    float dx[ETK_LIGHT_BATCH], dy[ETK_LIGHT_BATCH], dz[ETK_LIGHT_BATCH], pdf[ETK_LIGHT_BATCH];
    float Lr[ETK_LIGHT_BATCH], Lg[ETK_LIGHT_BATCH], Lb[ETK_LIGHT_BATCH];
    int row[ETK_LIGHT_BATCH], col[ETK_LIGHT_BATCH];
    etk_env_light_batch(etk_light_table(S, kind), S.env_texels, p.env, xu, xv, dx, dy, dz, pdf, Lr,
                        Lg, Lb, row, col);
    for (int k = 0; k < ETK_LIGHT_BATCH && first + k < n; ++k) // the map's tables have no cells
        etk_put_light_sample(P, Q.shade[first + k], dx[k], dy[k], dz[k], pdf[k], Lr[k], Lg[k],
                             Lb[k], 0);
}

// Shade step 1: the vertex in `slot` -- its surface (and, at the camera ray's hit, the AOVs), its
// light sample's source and expected counts.
ETK_STRUCT_INLINE_FN EtkVertex etk_shade_vertex(EtkScene S, EtkPaths P, EtkFilm F, EtkParams p,
                                                int slot) {
    EtkVertex v;
    v.slot = slot;
    v.depth = P.depth[slot];
    v.pixel = P.pixel[slot];
    v.s = etk_path_surface(S, P, p, slot);
    if (v.depth == 0) // the camera ray's hit: the AOVs
        etk_aov_first_hit(F, p, v.pixel, v.s, etk_xyz(P.ray_d[slot]), P.hit[slot].x);
    v.beta = etk_xyz(P.beta[slot]);
    v.pair = etk_vertex_pair(v.depth);
    v.last = etk_last_bounce(p, v.depth);
    v.delta = etk_bsdf_is_delta(v.s.m);
    v.bsdf_count = etk_last_bsdf_share(p, v.s.m, v.s.wo, v.last, v.delta);
    int kind = etk_light_kind(p, v.depth);
    // The cell as sample_lights found it, if it drew the light sample.
    int cell = p.light_batch ? P.light_cell[slot] : etk_light_cell(p, kind, v.s, v.s.m);
    v.light = etk_light_source(p, v.depth, cell);
    v.light_count = etk_light_count(S, p, v.light);
    // The guided share of the continuation; none at the last bounce, where the continuation
    // only gathers the map's light, which the light sample already draws from a learned table.
    v.guided = v.light.kind == ETK_LIGHT_LEARNED && !v.last
                   ? etk_cguide_share(S, p, v.light.cell, v.s.m)
                   : 0.0f;
    return v;
}

// Whether the vertex takes its light sample: always, unless its expected count is below 1; then
// on a sample dimension of its own.
ETK_FN int etk_takes_light_sample(EtkParams p, EtkVertex v) {
    if (v.delta || v.light.kind == ETK_LIGHT_NONE)
        return 0;
    return !(v.light_count < 1.0f) ||
           etk_dims(p, v.pixel, ETK_PAIR_SHARE + (uint)v.depth).x < v.light_count;
}

// The BSDF's density of a light sample's direction as MIS weighs it: the continuation's, a
// guided vertex's mixture with the learned directions (asked only there: the call's arguments
// cost ~65 instructions a light sample in GCC's native code even when it returns at once), and
// at a thinned last vertex the expected count times it.
ETK_STRUCT_INLINE_FN float etk_continuation_pdf(EtkScene S, EtkParams p, EtkVertex v, float3 wi,
                                                float3 wi_world) {
    float pb = v.bsdf_count * etk_bsdf_pdf(v.s.m, v.s.wo, wi);
    if (v.guided > 0.0f)
        pb = etk_cguide_mix_pdf(S, p, v.light.cell, v.guided, pb, etk_surface_origin(v.s, wi_world),
                                wi_world);
    return pb;
}

// A shadow ray's payload: its contribution if unblocked, and, for the learned technique's
// records, the unweighted value of its direction and where it points.
typedef struct {
    float3 dir, c;
    float value;
    int key;
    float2 parts; // p_vis and p_portal of the direction (portal_guide.h)
} EtkLightContribution;

// The vertex's one light sample from the light-sampling module, weighted by MIS against the
// continuation where the pass combines them. c is 0 where it brings nothing.
ETK_STRUCT_INLINE_FN EtkLightContribution etk_light_contribution(EtkScene S, EtkPaths P,
                                                                 EtkParams p, EtkVertex v) {
    EtkLightContribution r;
    r.c = make_float3(0.0f, 0.0f, 0.0f);
    r.value = 0.0f;
    r.key = 0;
    r.parts = make_float2(0.0f, 0.0f);
    // With the sample_lights stage the sample is drawn already, from this pair.
    int drawn = p.light_batch;
    EtkEnvSample ls =
        drawn ? etk_drawn_light_sample(P, v.slot)
              : etk_light_sample(S, p, v.light, v.s, etk_dims(p, v.pixel, v.pair), &r.parts);
    r.dir = ls.dir;
    float3 wi = etk_to_local(ls.dir, v.s.t, v.s.b, v.s.ns);
    // Above the surface, or below it at a dielectric (it transmits light from there).
    if (!(ls.pdf > 0.0f) || !etk_light_side_ok(v.s.m, wi.z, dot(ls.dir, v.s.ng)))
        return r;
    float3 f = etk_bsdf_eval(v.s.m, v.s.wo, wi);
    float w = 1.0f; // sample 0 of the vertex's light samples
    if (p.mis)
        w = etk_light_sample_weight(p, v.light_count, ls.pdf,
                                    etk_continuation_pdf(S, p, v, wi, ls.dir));
    float3 L = drawn ? etk_xyz(P.light_L[v.slot]) : etk_light_radiance(S, p, ls.uv);
    r.c = v.beta * f * L * (fabs(wi.z) * w / ls.pdf);
    if (p.guide_learn) { // what this direction would bring, unweighted, and where
        r.value = etk_luma(L) * fabs(wi.z) / ls.pdf;
        if (drawn && v.light.kind == ETK_LIGHT_LEARNED) { // etk_guide_light_batch left them
            r.key = P.shadow_key[v.slot];
            r.parts = P.guide_parts[v.slot];
        } else {
            r.key = etk_guide_record_key(p.env, v.light.cell, ls.uv);
        }
    }
    return r;
}

// SIS's light sample: one stratum per sample, every stratum once in each run of light_count
// samples, weighted by light_count x its power (directional_lights.h).
ETK_FN EtkLightContribution etk_strata_contribution(EtkScene S, EtkParams p, EtkVertex v) {
    EtkLightContribution r;
    int k = (int)(p.sample_index % (uint)p.light_count);
    float3 md = etk_dl_stratum_direction(S.strata_texels, S.strata_cdf, S.strata_begin[k],
                                         S.strata_begin[k + 1], p.strata_width, p.strata_height,
                                         etk_dims(p, v.pixel, v.pair));
    r.dir = normalize(etk_env_to_world(p.env, md));
    float3 E = etk_xyz(S.lights[2 * k + 1]) * (float)p.light_count;
    r.c = v.beta * etk_dl_unshadowed(v.s, r.dir, E);
    r.value = 0.0f;
    r.key = 0;
    r.parts = make_float2(0.0f, 0.0f);
    return r;
}

// Shade step 2: the vertex's light sample, pushed as a shadow ray if it could bring anything.
// Shadow rays stop at any surface, glass included: light through glass (caustics) is the
// continuation's to find, as indirect light, never the light sample's.
ETK_STRUCT_INLINE_FN void etk_shade_light(EtkScene S, EtkPaths P, EtkParams p, EtkVertex v,
                                          EtkPushes* out) {
    if (!etk_takes_light_sample(p, v))
        return;
    EtkLightContribution r = v.light.kind == ETK_LIGHT_STRATA ? etk_strata_contribution(S, p, v)
                                                              : etk_light_contribution(S, P, p, v);
    if (!(etk_max3(r.c) > 0.0f))
        return;
    int slot = v.slot;
    P.shadow_o[slot] = etk_f4(etk_surface_origin(v.s, r.dir), 0.0f);
    P.shadow_d[slot] = etk_f4(r.dir, 0.0f);
    P.shadow_L[slot] = etk_f4(r.c, 0.0f);
    if (p.guide_learn) {
        P.shadow_key[slot] = r.key;
        P.shadow_val[slot] = r.value;
        P.guide_parts[slot] = r.parts;
    }
    out->slot[ETK_Q_SHADOW] = slot;
}

// Shade step 3: split samples (etk_split_samples), added to the path's radiance at once.
ETK_FN void etk_shade_split(EtkScene S, EtkPaths P, EtkQueues Q, EtkParams p, EtkVertex v) {
    if (p.light_samples * p.bsdf_samples <= 1 || v.delta)
        return;
    uint traced = 0u;
    float3 e = etk_split_samples(S, p, v, &traced);
    if (traced > 0u) // counted with the light set's rays (traced in a shade stage too)
        ETK_COUNTER_ADD(Q.counters + ETK_Q_LIGHT_RAYS, traced);
    if (etk_max3(e) > 0.0f) {
        float4 r = P.radiance[v.slot];
        P.radiance[v.slot] = etk_f4(etk_xyz(r) + v.beta * e, r.w);
    }
}

// A vertex's continuation: its direction, f cos / pdf, the density it was drawn from (< 0: a
// delta sample), and the throughput Russian roulette weighs relative to beta.
typedef struct {
    float3 wi_world, weight;
    float wz; // the direction's cosine in the shading frame: < 0 for a transmission
    float pdf;
    float rr_scale;
    int ok; // 0: no sample
} EtkContinuation;

// The continuation's direction: at a guided vertex from the mixture of the cell's learned
// directions and the BSDF, else from the BSDF (at a thinned last vertex, one of expected count
// bsdf_count: density bsdf_count p_bsdf in the escaped ray's weight).
ETK_STRUCT_INLINE_FN EtkContinuation etk_continuation_sample(EtkScene S, EtkParams p, EtkVertex v,
                                                             float2 u, float lobe) {
    EtkContinuation c;
    c.ok = 0;
    c.rr_scale = 1.0f;
    EtkSurface s = v.s;
    if (v.guided > 0.0f) {
        EtkGuidedSample g = etk_cguide_sample_mixture(S, p, v.light.cell, v.guided, s.m, s, s.t,
                                                      s.b, s.ns, u, lobe);
        if (!(g.pdf > 0.0f) || !(g.pdf_bsdf > 0.0f))
            return c; // below the surface: nothing a diffuse surface reflects
        c.wi_world = g.wi_world;
        c.pdf = g.pdf;
        c.weight = etk_bsdf_eval(s.m, s.wo, g.wi) * (g.wi.z / g.pdf);
        c.wz = g.wi.z;
        // Russian roulette as if the BSDF had drawn the direction: a guided sample towards
        // bright light has a small weight (its density is high), and a survival probability
        // that followed it would cut exactly the paths the guide found.
        c.rr_scale = g.pdf / g.pdf_bsdf;
        c.ok = 1;
        return c;
    }
    EtkBsdfSample bs = etk_bsdf_sample(s.m, s.wo, u, lobe);
    if (!(bs.pdf > 0.0f))
        return c;
    c.wi_world = etk_from_local(bs.wi, s.t, s.b, s.ns);
    c.wz = bs.wi.z;
    c.weight = bs.weight;
    c.pdf = bs.pdf;
    if (v.bsdf_count < 1.0f) {
        c.weight = c.weight / v.bsdf_count;
        c.pdf = c.pdf * v.bsdf_count;
    }
    if (bs.delta)
        c.pdf = -1.0f;
    c.ok = 1;
    return c;
}

// Whether the vertex draws a continuation at all: not without the continuation switch (SIS: direct
// light only), nor at a last non-delta vertex whose continuation could only escape to a map its
// light sample alone accounts for; at a thinned last vertex with probability bsdf_count, chosen
// by a hash of the sample (a Sobol' pair would cost twice as much, and most of these samples are
// never drawn).
ETK_FN int etk_continues(EtkParams p, EtkVertex v) {
    if (!p.continuation)
        return 0;
    if (v.last && !v.delta && !p.mis && v.light.kind != ETK_LIGHT_NONE)
        return 0;
    return !(v.bsdf_count < 1.0f) || etk_last_bsdf_choice(p, v.pixel) < v.bsdf_count;
}

// Shade step 4: the continuation, pushed as the path's next ray unless it brings nothing or
// Russian roulette ends the path.
ETK_STRUCT_INLINE_FN void etk_shade_continue(EtkScene S, EtkPaths P, EtkParams p, EtkVertex v,
                                             EtkPushes* out) {
    if (!etk_continues(p, v))
        return;
    float2 rr = etk_dims(p, v.pixel, v.pair + 2u);
    EtkContinuation c = etk_continuation_sample(S, p, v, etk_dims(p, v.pixel, v.pair + 1u), rr.x);
    if (!c.ok || !etk_same_side(c.wz, dot(c.wi_world, v.s.ng)))
        return; // across the geometric surface from its shading side: would leak light
    // The last bounce's continuation can only bring back the map's light (no surface emits):
    // where the map is black for certain in its direction it would bring nothing, and is not
    // traced -- most of them under a map whose light is a few texels (a studio's lamps,
    // spot1Lux). A small mask rather than the texels: their lookup here would cost about what
    // the ray saves (cache misses in a large map). The image is the same to the bit.
    if (v.last && p.env.black_w > 0 &&
        etk_env_black_uv(S.env_black, p.env, etk_env_uv(p.env, normalize(c.wi_world))))
        return;
    float3 beta = v.beta * c.weight;
    // A refraction scales radiance by 1 / eta^2 (dielectric.h), into glass and back out again:
    // Russian roulette weighs the throughput without it (pbrt's etaScale), or paths inside glass
    // of index 1.5 would survive 1 in 2.25 and come out as fireflies of 2.25x their worth.
    float eta_scale = P.eta_scale[v.slot];
    if (etk_bsdf_is_dielectric(v.s.m) && c.wz < 0.0f)
        eta_scale *= v.s.m.eta * v.s.m.eta;
    // Russian roulette past the path's first rr_depth surfaces (this vertex is surface depth + 1).
    if (v.depth >= p.rr_depth) {
        float survive = fmin(0.95f, etk_max3(beta) * c.rr_scale * eta_scale);
        if (!(rr.y < survive))
            return;
        beta = beta / survive;
    }
    if (!(etk_max3(beta) > 0.0f) || !isfinite(etk_max3(beta)))
        return;
    int slot = v.slot;
    P.ray_o[slot] = etk_f4(etk_surface_origin(v.s, c.wi_world), 0.0f);
    P.ray_d[slot] = etk_f4(normalize(c.wi_world), 0.0f);
    P.depth[slot] = v.depth + 1;
    P.ray_pdf[slot] = c.pdf;
    P.ray_cell[slot] = v.light.cell;
    P.beta[slot] = etk_f4(beta, 0.0f);
    P.eta_scale[slot] = eta_scale;
    out->slot[ETK_Q_RAY_OUT] = slot;
}

// Stage 3: at a surface, one light sample (pushed as a shadow ray), split samples where asked,
// and one continuation (pushed as the path's next ray).
// Forced inline: PoCL otherwise keeps the stage a call per work-item, which copies the scene,
// path, queue, film and parameter structs (about a kilobyte, passed by value) on every call;
// inlined, its shade stage takes 5-9% less time (bunny_esplanade, depth 1 and 5) for a cold
// program build 4 s longer. GCC's native code is the same speed either way.
ETK_FORCE_INLINE_FN void etk_shade(ETK_STAGE_PARAMS) {
    EtkVertex v = etk_shade_vertex(S, P, F, p, Q.shade[i]);
    etk_shade_light(S, P, p, v, out);
    etk_shade_split(S, P, Q, p, v);
    etk_shade_continue(S, P, p, v, out);
}

// Stage 4: shadow rays add their contribution when nothing blocks them.
ETK_FN void etk_shadow(ETK_STAGE_PARAMS) {
    (void)out;
    (void)F;
    int slot = Q.shadow[i];
    float4 o = P.shadow_o[slot], d = P.shadow_d[slot];
    if (p.guide_learn)
        etk_guide_prefetch_light(Q.guide_sums, p, P.shadow_key[slot]);
    EtkHit h;
    int visible =
        !etk_bvh_traverse(S.nodes, S.packets, etk_xyz(o), etk_xyz(d), ETK_RAY_UNBOUNDED, 1, &h);
    if (visible) {
        float4 r = P.radiance[slot];
        P.radiance[slot] = etk_f4(etk_xyz(r) + etk_xyz(P.shadow_L[slot]), r.w);
    }
    if (p.guide_learn) { // the visibility strategy's record, summed on the device
        ETK_GLOBAL const float* box = etk_portal_table(S, p);
        float t; // where an unoccluded ray leaves the scene's box: the portal table's record
        int exit = visible ? etk_portal_exit(box, etk_xyz(o), etk_xyz(d), &t) : -1;
        float value = P.shadow_val[slot];
        etk_guide_record_light(Q.guide_sums, p, box, P.shadow_key[slot], visible ? value : 0.0f,
                               value, exit, P.guide_parts[slot]);
    }
}

// Stage 3': the shade stage of a directional light set (ETK_LIGHT_SET, direct lighting
// only): every light of the set at every hit, one any-hit shadow ray each, summed in light order.
ETK_FN void etk_shade_lights(ETK_STAGE_PARAMS) {
    (void)out;
    int slot = Q.shade[i];
    EtkSurface s = etk_path_surface(S, P, p, slot);
    if (P.depth[slot] == 0) // the camera ray's hit: the AOVs
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
        ETK_COUNTER_ADD(Q.counters + ETK_Q_LIGHT_RAYS, traced);
    float4 r = P.radiance[slot];
    P.radiance[slot] = etk_f4(etk_xyz(r) + beta * L, r.w);
}

// Stage 5: the pass's path radiance into the film. A non-finite sample counts as zero rather
// than poisoning the pixel, and is counted: the host reports any, and the tests require none.
ETK_FN void etk_accumulate(ETK_STAGE_PARAMS) {
    (void)out;
    int pixel = P.pixel[i];
    float3 L = etk_xyz(P.radiance[i]);
    if (!(isfinite(L.x) && isfinite(L.y) && isfinite(L.z))) {
        ETK_COUNTER_INC(Q.counters + ETK_Q_NONFINITE);
        L = make_float3(0.0f, 0.0f, 0.0f);
    }
    etk_film_add(F, pixel, L);
    if (p.guide_learn && p.guide_continuation) // the path's continuation records
        etk_guide_record_path(S, P, Q.guide_sums, p, i);
}

// A wave counted on the device (host/lib/render/schedule.cpp) enqueues every bounce's stages
// without reading the queues' sizes back: each stage is launched for the most work-items its
// queue could hold, and those past the size its counter holds return at once. Between two
// bounces etk_next_bounce (one work-item) makes the continuation rays queued by the last one
// this one's input (first_rays >= 0: the wave's camera rays, the first bounce) and moves the
// last bounce's counts into the sums the host reads at the end of the wave.
ETK_FN void etk_next_bounce(ETK_COUNTER_PTR c, int first_rays) {
    uint in = first_rays >= 0 ? (uint)first_rays : c[ETK_Q_RAY_OUT];
    if (first_rays < 0)
        c[ETK_Q_SUM_RAYS_IN] += in;
    c[ETK_Q_SUM_SHADE] += c[ETK_Q_SHADE];
    c[ETK_Q_SUM_SHADOW] += c[ETK_Q_SHADOW] + c[ETK_Q_LIGHT_RAYS];
    c[ETK_Q_RAY_IN] = in;
    c[ETK_Q_RAY_OUT] = 0u;
    c[ETK_Q_SHADOW] = 0u;
    c[ETK_Q_SHADE] = 0u;
    c[ETK_Q_LIGHT_RAYS] = 0u;
}
// The work-items of `stage` in a wave counted on the device: the size of the queue it reads (in
// light-sample batches for sample_lights); -1 for the stages the host sizes (generate,
// accumulate: one work-item per path of the wave).
ETK_FN int etk_counted_items(ETK_COUNTER_PTR c, int stage) {
    if (stage == ETK_STAGE_intersect)
        return (int)c[ETK_Q_RAY_IN];
    if (stage == ETK_STAGE_sample_lights)
        return etk_light_batch_items(c[ETK_Q_SHADE]);
    if (stage == ETK_STAGE_shade_hits || stage == ETK_STAGE_shade_lights)
        return (int)c[ETK_Q_SHADE];
    if (stage == ETK_STAGE_trace_shadows)
        return (int)c[ETK_Q_SHADOW];
    return -1;
}

ETK_END

#endif
