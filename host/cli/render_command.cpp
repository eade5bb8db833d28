#include "commands.h"
#include "env_sampling.h"
#include "error.h"
#include "json_file.h"
#include "kernels/sampler.h"
#include "preview.h"
#include "scene_environment.h"

#include <cstdio>
#include <filesystem>

namespace et::cli {
namespace {

struct RenderArgs {
    std::string scene, output;
};

// Until the path tracer lands (issue 3), `render` shows what it will be lit by: the scene's
// environment with its importance samples drawn on it.
void run(const RenderArgs& a, const Globals& g) {
    nlohmann::json scene = read_json_file(a.scene);
    const std::string dir = std::filesystem::path(a.scene).parent_path().string();
    if (!scene.contains("environment"))
        throw Error(a.scene + ": no \"environment\" block");
    EnvMap env = load_scene_environment(scene["environment"], dir, a.scene, {});
    std::printf("environment %s: %dx%d, distribution built in %.2f ms\n", env.name.c_str(),
                env.image.width, env.image.height, env.build_seconds * 1e3);
    std::printf("note: the path tracer is not implemented yet; drawing the environment's "
                "importance samples instead\n");
    ClRuntime rt(g.device);
    ProgramBuildInfo build;
    EnvSamplerCL sampler(rt, env, &build);
    auto samples = sampler.sample_sequence(ETK_SAMPLER_SOBOL, 1, 0, 0, 256);
    std::vector<float> display = tone_map(env.image);
    const float colour[3] = {1.0f, 0.15f, 0.1f};
    for (const auto& s : samples) {
        if (!(s.pdf > 0.0f))
            continue;
        etk::float2 uv = etk::etk_dir_to_latlong(
            etk::etk_world_to_env(env.desc(), etk::make_float3(s.dir[0], s.dir[1], s.dir[2])));
        draw_dot(display, env.image.width, env.image.height, uv.x, uv.y,
                 std::max(1, env.image.width / 256), colour);
    }
    std::string out =
        a.output.empty() ? std::filesystem::path(a.scene).stem().string() + ".png" : a.output;
    write_image(out, env.image.width, env.image.height, 3, display);
    std::printf("program build %.3f s (%s); wrote %s\n", build.seconds,
                build.from_cache ? "cached" : "compiled", out.c_str());
}

} // namespace

void add_render_command(CLI::App& app, Globals& g) {
    auto a = std::make_shared<RenderArgs>();
    auto* cmd = app.add_subcommand("render", "Render a scene file");
    cmd->add_option("scene", a->scene, "Scene file (.json)")->required();
    cmd->add_option("-o,--output", a->output, "Output image (default: SCENE.png)");
    cmd->callback([a, &g] { run(*a, g); });
}

} // namespace et::cli
