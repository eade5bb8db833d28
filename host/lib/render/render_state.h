// A render's resumable state: the film's sums, the range of sample indices they hold, and a key
// of everything the film depends on. The sampler is a function of pixel, sample index and
// dimension, and the sums are exact (film_sums.h), so a render resumed from a state and run to
// N samples is bit-identical to one that ran to N without a break (Renderer::resume), and the
// states of disjoint sample ranges (farm tasks, `render --sample-range`) add up to the film of
// their union (`envtrace merge`).
#pragma once
#include "prepare/device_scene.h"
#include "render/film_sums.h"

#include <cstdint>
#include <string>

namespace et {

class OutputBatch;

// A hash (XXH3, 64 bits) of what the film's values depend on: every scene buffer, the per-pass
// parameters (camera, film size, environment, depth, strategy, heuristic, sampler, seed), the
// back end and device, and envtrace's version and kernel sources. Not the target spp, time
// limit, paths in flight, threads or light-sample batching, which do not change any sample.
uint64_t render_key(const DeviceScene& scene);

struct RenderState {
    uint64_t key = 0;
    int spp = 0;   // samples per pixel in the film: sample indices first .. first + spp - 1
    int first = 0; // the first sample index (0 but for a part of a render, --sample-range)
    FilmSums sums;
    // The samples of the whole render this film is part of (indices 0 .. total-1): what --spp
    // asked for (a farm task's --spp, else the end of its range); 0 where no end was asked for
    // (--time-limit, --noise-target) or the state is older than this field. merge checks that
    // its parts cover it.
    int total = 0;
};

// Writes the state as one file of `batch` (binary: header, film sums, checksum).
void write_render_state(OutputBatch& batch, const std::string& path, const RenderState& state);
// Written on its own, atomically.
void write_render_state(const std::string& path, const RenderState& state);

// Reads a state; throws et::Error naming the file on anything but an intact state file.
RenderState read_render_state(const std::string& path);

// Throws et::Error unless `state` continues a render of `scene` (same key and film size).
void check_render_state(const RenderState& state, const DeviceScene& scene,
                        const std::string& path);

} // namespace et
