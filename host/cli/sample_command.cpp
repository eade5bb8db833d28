#include "commands.h"
#include "render/env_sampling.h"
#include "util/error.h"
#include "kernels/sampler.h"
#include "image/image_io.h"
#include "image/preview.h"
#include "util/output_batch.h"
#include "prepare/device_scene.h"
#include "util/timer.h"

#include <cstdio>
#include <iostream>

namespace et::cli {
namespace {

struct SampleArgs {
    std::string map, output = "points.png", sampler = "sobol", dist_res;
    int count = 128;
    unsigned seed = 1;
    float blur = 0.5f;
};

void run(const SampleArgs& a, const Globals& g) {
    check_writable_format(a.output); // before the map, the device and the samples
    DistributionOptions opt;
    opt.blur_sigma = a.blur;
    if (!a.dist_res.empty())
        parse_resolution(a.dist_res, opt.width, opt.height);
    EnvMap env = load_envmap(a.map, opt);
    std::printf("map %s: %dx%d, distribution %dx%d (blur sigma %.2f texels)\n", a.map.c_str(),
                env.image.width, env.image.height, env.dist.width, env.dist.height, a.blur);
    std::printf("load %.1f ms, precompute (distribution build) %.2f ms\n", env.load_seconds * 1e3,
                env.build_seconds * 1e3);

    ClRuntime rt(g.device);
    ProgramBuildInfo build;
    EnvSamplerCL sampler(rt, env, &build);
    Timer t;
    auto samples = sampler.sample_sequence(static_cast<int>(parse_sampler(a.sampler, "--sampler")),
                                           a.seed, 0, 0, a.count);
    const double sample_s = t.seconds();
    std::printf("device %s: program build %.3f s (%s), %d samples in %.2f ms\n",
                rt.device().device_name.c_str(), build.seconds,
                build.from_cache ? "cached binary" : "compiled", a.count, sample_s * 1e3);
    if (!env.dist.has_light())
        std::printf("the map emits no light: no samples to draw\n");

    std::vector<std::array<float, 3>> dirs;
    for (const auto& s : samples)
        if (s.pdf > 0.0f)
            dirs.push_back({s.dir[0], s.dir[1], s.dir[2]});
    OutputBatch outputs({a.output});
    write_direction_plot(outputs, a.output, env, dirs);
    outputs.commit();
    std::printf("wrote %s\n", a.output.c_str());
}

} // namespace

void add_sample_command(CLI::App& app, Globals& g) {
    auto a = std::make_shared<SampleArgs>();
    auto* cmd = app.add_subcommand(
        "sample", "Draw importance samples from an environment map and plot them (paper, Fig. 6)");
    cmd->add_option("map", a->map, "Lat-long environment map (.exr, .hdr, .pfm, .png, .jpg)")
        ->required();
    cmd->add_option("-n,--count", a->count, "Number of samples")
        ->check(CLI::Range(0, 1 << 22)); // 4M points: ~330 MB of samples on host and device
    cmd->add_option("-o,--output", a->output, "Output image (.png, .jpg, .exr, ...)");
    cmd->add_option("--sampler", a->sampler, "sobol (scrambled (0,2)-sequence) or random")
        ->check(CLI::IsMember({"sobol", "random"}));
    cmd->add_option("--seed", a->seed, "Scrambling / random seed");
    cmd->add_option("--dist-res", a->dist_res, "Distribution resolution WxH (default: the map's)");
    cmd->add_option("--blur", a->blur, "Gaussian blur sigma of the luminance, in texels (0: none)")
        ->check(finite_range(0.0, 64.0));
    cmd->callback([a, &g] { run(*a, g); });
}

} // namespace et::cli
