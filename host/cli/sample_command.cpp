#include "commands.h"
#include "env_sampling.h"
#include "error.h"
#include "kernels/sampler.h"
#include "preview.h"
#include "timer.h"

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

int parse_sampler(const std::string& name) {
    if (name == "sobol")
        return ETK_SAMPLER_SOBOL;
    if (name == "random")
        return ETK_SAMPLER_RANDOM;
    throw Error("unknown sampler '" + name + "' (use sobol or random)");
}

void run(const SampleArgs& a, const Globals& g) {
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
    auto samples = sampler.sample_sequence(parse_sampler(a.sampler), a.seed, 0, 0, a.count);
    const double sample_s = t.seconds();
    std::printf("device %s: program build %.3f s (%s), %d samples in %.2f ms\n",
                rt.device().device_name.c_str(), build.seconds,
                build.from_cache ? "cached binary" : "compiled", a.count, sample_s * 1e3);
    if (!env.dist.has_light())
        std::printf("the map emits no light: no samples to draw\n");

    std::vector<float> display = tone_map(env.image);
    const int radius = std::max(1, env.image.width / 256);
    const float colour[3] = {1.0f, 0.15f, 0.1f};
    for (const auto& s : samples) {
        if (!(s.pdf > 0.0f))
            continue;
        etk::float3 d =
            etk::etk_world_to_env(env.desc(), etk::make_float3(s.dir[0], s.dir[1], s.dir[2]));
        etk::float2 uv = etk::etk_dir_to_latlong(d);
        draw_dot(display, env.image.width, env.image.height, uv.x, uv.y, radius, colour);
    }
    write_image(a.output, env.image.width, env.image.height, 3, display,
                {{"Software", "envtrace " ENVTRACE_VERSION}});
    std::printf("wrote %s\n", a.output.c_str());
}

} // namespace

void add_sample_command(CLI::App& app, Globals& g) {
    auto a = std::make_shared<SampleArgs>();
    auto* cmd = app.add_subcommand(
        "sample", "Draw importance samples from an environment map and plot them (paper, Fig. 6)");
    cmd->add_option("map", a->map, "Lat-long environment map (.exr, .hdr, .pfm, .png, .jpg)")
        ->required();
    cmd->add_option("-n,--count", a->count, "Number of samples")->check(CLI::Range(0, 100000000));
    cmd->add_option("-o,--output", a->output, "Output image (.png, .jpg, .exr, ...)");
    cmd->add_option("--sampler", a->sampler, "sobol (scrambled (0,2)-sequence) or random")
        ->check(CLI::IsMember({"sobol", "random"}));
    cmd->add_option("--seed", a->seed, "Scrambling / random seed");
    cmd->add_option("--dist-res", a->dist_res, "Distribution resolution WxH (default: the map's)");
    cmd->add_option("--blur", a->blur, "Gaussian blur sigma of the luminance, in texels (0: none)")
        ->check(CLI::Range(0.0f, 64.0f));
    cmd->callback([a, &g] { run(*a, g); });
}

} // namespace et::cli
