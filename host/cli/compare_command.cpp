#include "commands.h"
#include "util/json_file.h"
#include "util/output_batch.h"
#include "util/error.h"
#include "image/image_metrics.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>

namespace et::cli {
namespace {

struct CompareArgs {
    std::string a, b, mask, json;
};

// NaN or Inf in either image makes every metric meaningless (an all-NaN image would compare as
// 'l2 0'): refused, naming the file.
void require_finite(const RgbImage& img, const std::string& path) {
    size_t bad = 0;
    for (float v : img.rgb)
        bad += !std::isfinite(v);
    if (bad)
        throw Error(path + ": " + std::to_string(bad) + " of " + std::to_string(img.rgb.size()) +
                    " values are NaN or infinite: cannot compare");
}

void run(const CompareArgs& args) {
    RgbImage a = read_rgb_image(args.a);
    require_finite(a, args.a);
    RgbImage b = read_rgb_image(args.b);
    require_finite(b, args.b);
    if (a.width != b.width || a.height != b.height)
        throw Error(args.a + " is " + std::to_string(a.width) + "x" + std::to_string(a.height) +
                    " but " + args.b + " is " + std::to_string(b.width) + "x" +
                    std::to_string(b.height) + ": cannot compare images of different sizes");
    std::vector<unsigned char> mask;
    if (!args.mask.empty()) {
        mask = read_mask(args.mask, a.width, a.height);
        // A mask that selects nothing would report a perfect match ('l2 0') of no pixels.
        if (std::find(mask.begin(), mask.end(), 1) == mask.end())
            throw Error(args.mask + ": the mask selects no pixel (none has a first channel > "
                                    "0.5): nothing to compare");
    }
    // A --json over an input (or into a missing folder) fails before any metric is printed.
    std::optional<OutputBatch> batch;
    if (!args.json.empty())
        batch.emplace(std::vector<std::string>{args.json});
    const ImageErrors e = compare_images(a, b, mask);
    // l2 divides by the reference's norm: against a black reference it is infinite, which the
    // JSON could only write as null. Refused, like the other comparisons without a meaning.
    if (!std::isfinite(e.l2)) {
        char rmse[32];
        std::snprintf(rmse, sizeof rmse, "%.6g", e.rmse);
        throw Error(args.b + ": the reference is black" +
                    (args.mask.empty() ? std::string() : " where " + args.mask + " selects") +
                    ": the relative error l2 is undefined (rmse " + rmse +
                    "); compare against a reference with light in it");
    }
    std::printf("pixels %zu\nrmse %.6g\nrel_mse %.6g\nl2 %.6g\nmean %.6g (reference %.6g)\n",
                e.pixels, e.rmse, e.rel_mse, e.l2, e.mean_a, e.mean_b);
    if (!args.json.empty()) {
        nlohmann::json j{{"image", args.a},
                         {"reference", args.b},
                         {"mask", args.mask},
                         {"pixels", e.pixels},
                         {"rmse", e.rmse},
                         {"rel_mse", e.rel_mse},
                         {"rel_mse_epsilon", kRelMseEpsilon},
                         {"l2", e.l2},
                         {"mean", e.mean_a},
                         {"reference_mean", e.mean_b}};
        write_json_file(*batch, args.json, j, 2);
        batch->commit();
    }
}

} // namespace

void add_compare_command(CLI::App& app, Globals&) {
    auto a = std::make_shared<CompareArgs>();
    auto* cmd = app.add_subcommand(
        "compare", "Error of image A against reference B: RMSE, relative MSE and relative L2");
    cmd->add_option("image", a->a, "Image to evaluate (.exr, .hdr, .pfm, ...)")->required();
    cmd->add_option("reference", a->b, "Reference image of the same size")->required();
    cmd->add_option("--mask", a->mask, "Only pixels where this image's first channel is > 0.5");
    cmd->add_option("--json", a->json, "Also write the metrics as JSON");
    cmd->callback([a] { run(*a); });
}

} // namespace et::cli
