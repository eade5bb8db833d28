#include "commands.h"
#include "util/error.h"
#include "util/file_check.h"
#include "image/image_io.h"
#include "kernels/latlong.h"
#include "prepare/light_set.h"
#include "image/preview.h"
#include "util/output_batch.h"

#include <cstdio>
#include <string>
#include <vector>

namespace et::cli {
namespace {

struct LightsArgs {
    std::string map, output = "lights.json", method = "ours", power = "share", plot;
    int count = 32, sis_levels = 6;
    unsigned seed = 1;
    float blur = 0.5f;
};

void run(const LightsArgs& a) {
    // The plot's name is checked before any work, and the outputs land together or not at all:
    // a bad --plot leaves no light set behind.
    if (!a.plot.empty())
        check_writable_format(a.plot);
    // The light set is JSON: under another name ("-o lights.exr") it would pass for an image.
    if (lower_extension(a.output) != ".json")
        throw Error(a.output + ": the light set is written as JSON: name it .json (--plot "
                               "writes an image of the directions)");
    DistributionOptions opt;
    opt.blur_sigma = a.blur;
    EnvMap env = load_envmap(a.map, opt);
    // Reserved before the selection (SIS takes seconds for thousands of lights): a missing folder
    // or an output over the map fails first. After the map is read, so that it is known as an
    // input.
    OutputBatch outputs(a.plot.empty() ? std::vector<std::string>{a.output}
                                       : std::vector<std::string>{a.output, a.plot});
    LightSet set;
    if (a.method == "ours") {
        set = make_lights_ours(env, a.count, a.seed, a.power == "voronoi");
    } else {
        SisOptions o;
        o.levels = a.sis_levels;
        set = make_lights_sis(env, a.count, o);
    }
    write_lights(outputs, a.output, set);
    if (!a.plot.empty()) {
        std::vector<std::array<float, 3>> dirs;
        for (const auto& l : set.lights)
            dirs.push_back({float(l.direction.x), float(l.direction.y), float(l.direction.z)});
        write_direction_plot(outputs, a.plot, env, dirs);
    }
    outputs.commit();
    glm::dvec3 sum(0.0);
    for (const auto& l : set.lights)
        sum += l.power;
    std::printf("map %s: %dx%d, power (integral of L) %.6g %.6g %.6g\n", a.map.c_str(),
                env.image.width, env.image.height, set.map_power.x, set.map_power.y,
                set.map_power.z);
    std::printf("%zu lights by %s (power: %s), sum of powers %.6g %.6g %.6g\n", set.lights.size(),
                set.method.c_str(), set.power_rule.c_str(), sum.x, sum.y, sum.z);
    std::printf("precompute %.4f s + selection %.4f s = %.4f s\n", set.precompute_seconds,
                set.selection_seconds, set.total_seconds());
    std::printf("wrote %s\n", a.output.c_str());
    if (!a.plot.empty())
        std::printf("wrote %s\n", a.plot.c_str());
}

} // namespace

void add_lights_command(CLI::App& app, Globals&) {
    auto a = std::make_shared<LightsArgs>();
    auto* cmd = app.add_subcommand(
        "lights", "Turn an environment map into N directional lights (paper, Figure 8)");
    cmd->add_option("map", a->map, "Lat-long environment map")->required();
    cmd->add_option("-n,--count", a->count, "Number of lights")->check(CLI::Range(1, 1 << 20));
    cmd->add_option("-o,--output", a->output, "Light set (.json) for 'envtrace render --lights'");
    cmd->add_option("--method", a->method,
                    "ours (warped low-discrepancy points) or sis (structured importance sampling)")
        ->check(CLI::IsMember({"ours", "sis"}));
    cmd->add_option("--power", a->power,
                    "ours: share (each sample's L/(N pdf), rescaled to the map's power) or "
                    "voronoi (each light's Voronoi cell)")
        ->check(CLI::IsMember({"share", "voronoi"}));
    cmd->add_option("--seed", a->seed, "Scrambling seed of the (0,2)-sequence (ours)");
    cmd->add_option("--blur", a->blur, "Gaussian blur sigma of the sampling luminance, texels")
        ->check(finite_range(0.0, 64.0));
    cmd->add_option("--sis-levels", a->sis_levels, "SIS brightness levels")
        ->check(CLI::Range(1, 64));
    cmd->add_option("--plot", a->plot, "Also draw the light directions on the map (.png)");
    cmd->callback([a] { run(*a); });
}

} // namespace et::cli
