// Adaptive allocation between light and BSDF sampling (the paper's future work; the adaptive
// strategy of kernels/integrator.h): per material bin, the expected number s of light samples
// among the two a vertex draws, learned from the first passes by measuring, not by modelling.
//
// During the learning passes every pixel renders with one of ETK_SHARE_CANDIDATES shares, picked
// by a hash of the pixel (etk_learning_candidate: neighbouring pixels try different shares).
// Two passes of a pixel are two independent samples of its estimator, so (x1 - x2)^2 / 2 is an
// unbiased estimate of that estimator's variance -- with every term in it: the correlation of
// the two samples of a vertex, the MIS weights, visibility, later bounces. Per material bin (of
// the pixel's first hit, the same in both passes) and candidate, the mean of these estimates,
// each weighted by 1 / (m^2 + eps) (m: the pixel's mean luminance over the other learning
// passes, independent of the pair) so that the objective is the relative variance that the eye
// and the efficiency harness see, each capped at 50x the bin's median (heavy tails), picks the
// candidate: a share, a light distribution (full or compensated) and a
// GGX sampling (kernels/params.h, etk_learning_share and etk_learning_flags). Every candidate is
// a reasonable estimator (candidate 0 is the paper's), so the learning passes, which are part of
// the image, cost little even where a candidate loses.
//
// Every learning pass is an unbiased sample like any other (each candidate is), and nothing is
// summed across threads: the shares depend on the seed alone -- not on threads, timing or wave
// size -- and any process derives them by rendering the learning passes itself.
#pragma once
#include "kernels/params.h"
#include "kernels/path_state.h"

#include <array>
#include <cstdint>
#include <vector>

namespace et {

using etk::float4;

struct LightShareOptions {
    int learning_passes = 16; // samples 0 .. 15
    int block = 4;            // compared in pairs of 4-pass blocks: (0-3, 4-7), (8-11, 12-15)
    int min_pixels = 16;      // pixel pairs every candidate of a bin needs to be compared
    bool last_bounce = true;  // first hits are the last bounce (max_depth 1)
};

class LightShareLearner {
  public:
    LightShareLearner(const LightShareOptions& options, int width, int height, uint32_t seed);

    // The first-hit bins of the pass in progress, by pixel (run_wave writes them).
    int* bins_of_pass() { return bins_.back().data(); }
    // Before a learning pass.
    void begin_pass();
    // After it: the pass's film (one sample per pixel: RGB, w the count; kernels/film.h).
    void end_pass(const std::vector<float4>& pass);
    // After the last learning pass: the winning candidate per bin (kDefaultCandidate where a
    // bin has too few pixels to compare).
    static constexpr int kDefaultCandidate = 2; // the compensated strategy
    std::array<int, ETK_SHARE_BINS> choices() const;

    // The measured mean weighted variance of candidate k in `bin` and its pixel count (tests).
    struct Cell {
        double sum = 0.0;
        uint64_t pixels = 0;
    };
    std::array<std::array<Cell, ETK_SHARE_CANDIDATES>, ETK_SHARE_BINS> measure() const;

  private:
    LightShareOptions opt_;
    int width_, height_;
    uint32_t seed_;
    std::vector<std::vector<int>> bins_;         // per pass, per pixel
    std::vector<std::vector<float>> values_;     // per pass, per pixel: the sample's luminance
    double image_sum_ = 0.0, image_count_ = 0.0; // luminance of every learning sample
};

} // namespace et
