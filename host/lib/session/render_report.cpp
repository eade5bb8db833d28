#include "session/render_report.h"

#include "render/learning_summary.h"
#include "util/interrupt.h"

#include <algorithm>
#include <cstdio>

namespace et {
namespace {

using json = nlohmann::json;

// The learning technique's verdict (render/guide_verdict.h), as the stats and the EXR name it.
std::string verdict_name(const RenderStats& s) {
    return s.learning.contains("verdict") ? s.learning["verdict"].get<std::string>() : "none";
}

// Which samples, how long, and how the render ended.
void add_run_facts(RenderReport& r, const ReportInputs& in) {
    const RenderSession& s = in.session;
    const SessionResult& res = in.result;
    const DeviceScene& ds = s.prepared().scene;
    const int rendered = res.spp - res.resumed_from;
    r.push_back({"/scene", "", s.options().scene, ""});
    r.push_back({"/backend", "envtrace:backend", s.renderer().name(), ""});
    r.push_back({"/ranks", "envtrace:ranks", in.ranks, ""});
    r.push_back({"/width", "", ds.width(), ""});
    r.push_back({"/height", "", ds.height(), ""});
    r.push_back({"/spp", "envtrace:spp", res.spp, ""});
    r.push_back({"/first_sample", "", res.first, ""});
    r.push_back({"/resumed_from_spp", "envtrace:resumed_from_spp", res.resumed_from, ""});
    r.push_back(
        {"/interrupted", "envtrace:interrupted", res.signal ? signal_name(res.signal) : "no", ""});
    // A pass abandoned at a signal or the time limit: its time and rays are counted.
    r.push_back({"/stopped_inside_a_pass", "", res.stopped, ""});
    r.push_back({"/aovs", "", s.settings().aovs, ""});
    r.push_back({"/render_seconds", "envtrace:render_seconds", res.render_seconds, ""});
    r.push_back({"/seconds_per_spp", "", res.render_seconds / std::max(1, rendered), ""});
}

// The estimator's settings, resolved as the render used them.
void add_settings_facts(RenderReport& r, const ReportInputs& in) {
    const RenderSettings& st = in.session.settings();
    r.push_back({"/max_depth", "envtrace:max_depth", st.max_depth, ""});
    r.push_back({"/rr_depth", "envtrace:rr_depth", st.rr_depth, ""});
    r.push_back({"/strategy", "envtrace:strategy", name_of(st.strategy), ""});
    r.push_back({"/sampler", "envtrace:sampler", name_of(st.sampler), ""});
    r.push_back({"/mis_heuristic", "envtrace:mis_heuristic", name_of(resolved_heuristic(st)), ""});
    r.push_back(
        {"/bsdf_sampling", "envtrace:bsdf_sampling", name_of(resolved_bsdf_sampling(st)), ""});
    r.push_back({"/light_batch", "", in.session.renderer().batches_light_samples(), ""});
    r.push_back({"/film_sums_on_device", "", in.session.renderer().sums_on_device(), ""});
    r.push_back(
        {"/queue_counts_on_device", "", in.session.renderer().queue_counts_on_device(), ""});
    // Per vertex (mis splitting; 1: the paper's).
    r.push_back({"/light_samples", "envtrace:light_samples", st.light_samples, ""});
    r.push_back({"/bsdf_samples", "envtrace:bsdf_samples", st.bsdf_samples, ""});
    r.push_back({"", "envtrace:seed", st.seed, ""});
}

// A learning technique's figures (LearningPolicy::stats) and the passes rendered only to learn.
json learning_facts(const RenderStats& s) {
    json j = s.learning;
    j["learning_passes_extra"] = s.learning_passes;
    j["summary"] = learning_summary(s.learning);
    return j;
}

// What the light set, SIS and visibility strategies add.
void add_strategy_facts(RenderReport& r, const ReportInputs& in) {
    const PreparedRender& p = in.session.prepared();
    const RenderSettings& st = in.session.settings();
    const RenderStats& s = in.result.stats;
    const bool lights = st.strategy == Strategy::lights, sis = st.strategy == Strategy::sis;
    r.push_back({lights ? "/lights/file" : "", "envtrace:lights", st.lights, ""});
    if (lights)
        r.push_back({"/lights/count", "", p.light_set.lights.size(), ""});
    if (sis) {
        r.push_back({"/sis/samples", "", st.sis_samples, ""});
        r.push_back({"/sis/level_samples", "", p.sis.level_samples, ""});
    }
    r.push_back({sis ? "/sis/precompute_seconds" : "", "envtrace:sis_seconds", p.sis.seconds, ""});
    if (!s.learning.is_null())
        r.push_back({std::string("/") + name_of(st.strategy), "", learning_facts(s), ""});
    r.push_back({"", "envtrace:visibility_verdict", verdict_name(s), ""});
}

// Rays, rates and the time spent building.
void add_performance_facts(RenderReport& r, const ReportInputs& in) {
    const DeviceScene& ds = in.session.prepared().scene;
    const RenderStats& s = in.result.stats;
    const double secs = in.result.render_seconds;
    const int rendered = in.result.spp - in.result.resumed_from;
    r.push_back({"/nonfinite_samples", "", s.nonfinite_samples, ""});
    r.push_back({"/rays",
                 "",
                 {{"camera", s.camera_rays},
                  {"continuation", s.continuation_rays},
                  {"shadow", s.shadow_rays}},
                 ""});
    r.push_back({"/mrays_per_second", "", s.rays() / secs * 1e-6, ""});
    r.push_back(
        {"/samples_per_second", "", double(rendered) * ds.width() * ds.height() / secs, ""});
    r.push_back({"/program_build_seconds", "", in.build.seconds, ""});
    r.push_back({"/program_from_cache", "", in.build.from_cache, ""});
    r.push_back({"/bvh",
                 "",
                 {{"nodes", ds.bvh.nodes},
                  {"depth", ds.bvh.depth},
                  {"sah_cost", ds.bvh.sah_cost},
                  {"build_seconds", ds.bvh.build_seconds}},
                 ""});
    r.push_back({"/environment_build_seconds", "", ds.map_build_seconds, ""});
    if (!s.stage_seconds.empty()) {
        json stages = json::object();
        for (const auto& [name, t] : s.stage_seconds)
            stages[name] = t;
        r.push_back({"/stage_seconds", "", stages, ""});
    }
}

// The noise target: in the stats only when one was asked for; the image always says.
void add_noise_facts(RenderReport& r, const ReportInputs& in) {
    const double target = in.session.options().noise_target;
    const bool noise = target > 0;
    const double error = in.result.noise_error;
    char text[32];
    std::snprintf(text, sizeof text, "%.6g", error);
    r.push_back({noise ? "/noise_target/target" : "", "envtrace:noise_target",
                 noise ? json(target) : json("none"), ""});
    r.push_back({noise ? "/noise_target/reached" : "", "envtrace:noise_target_reached",
                 in.result.noise_reached, ""});
    r.push_back({noise ? "/noise_target/estimated_relative_error" : "", "envtrace:noise_error",
                 error, text});
}

// The environment as the scene set it, and what wrote the image.
void add_environment_facts(RenderReport& r, const ReportInputs& in) {
    const PreparedRender& p = in.session.prepared();
    r.push_back({"", "envtrace:environment", p.scene.map_name, ""});
    r.push_back({"", "envtrace:environment_rotation_degrees", p.env_rotation_degrees, ""});
    r.push_back({"", "envtrace:environment_convention", p.env_convention, ""});
    r.push_back({"", "envtrace:environment_intensity", p.env_intensity, ""});
    r.push_back({"", "Software", "envtrace " ENVTRACE_VERSION, ""});
}

std::string metadata_text(const ReportFact& f) {
    if (!f.exr_text.empty())
        return f.exr_text;
    const json& v = f.value;
    if (v.is_string())
        return v.get<std::string>();
    if (v.is_boolean())
        return v.get<bool>() ? "yes" : "no";
    if (v.is_number_unsigned())
        return std::to_string(v.get<uint64_t>());
    if (v.is_number_integer())
        return std::to_string(v.get<int64_t>());
    if (v.is_number_float())
        return std::to_string(v.get<double>());
    return v.dump();
}

} // namespace

RenderReport render_report(const ReportInputs& in) {
    RenderReport r;
    add_run_facts(r, in);
    add_settings_facts(r, in);
    add_strategy_facts(r, in);
    add_performance_facts(r, in);
    add_noise_facts(r, in);
    add_environment_facts(r, in);
    return r;
}

nlohmann::json report_json(const RenderReport& report) {
    json j = json::object();
    for (const ReportFact& f : report)
        if (!f.json.empty())
            j[json::json_pointer(f.json)] = f.value;
    return j;
}

std::vector<std::pair<std::string, std::string>> report_metadata(const RenderReport& report) {
    std::vector<std::pair<std::string, std::string>> meta;
    for (const ReportFact& f : report)
        if (!f.exr.empty())
            meta.emplace_back(f.exr, metadata_text(f));
    return meta;
}

} // namespace et
