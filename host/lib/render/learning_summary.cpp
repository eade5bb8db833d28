#include "render/learning_summary.h"

#include <cmath>
#include <cstdio>

namespace et {

namespace {

std::string technique(const std::string& name) {
    return name == "tables" ? "the learned tables" : "`" + name + "`";
}

std::string possessive(const std::string& name) {
    return name == "tables" ? "the learned tables'" : "`" + name + "`'s";
}

std::string figure(const char* format, double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, format, v);
    return buf;
}

// What the verdict weighed: the fallback's error against the kept technique's, and the cost
// the kept one had to earn.
std::string measured(const nlohmann::json& l, const std::string& kept) {
    const std::string fallback = possessive(l.value("verdict_fallback", "fallback"));
    const double kept_error = l.value("verdict_kept_error", 0.0);
    const double fallback_error = l.value("verdict_fallback_error", 0.0);
    const std::string cost =
        ", against a cost of " + figure("%.3g", l.value("verdict_cost", 1.0)) + "x";
    if (!(kept_error > 0.0))
        return "measured: " + possessive(kept) + " error 0, " + fallback + " " +
               figure("%.3g", fallback_error) + cost;
    // The ratio's uncertainty: the factor of one standard error of its log (the verdict demands
    // that the ratio beat the cost by it); none below half a percent.
    const double se = l.value("verdict_log_ratio_se", 0.0);
    const std::string uncertain =
        se >= 0.005 ? ", uncertain by a factor of " + figure("%.3g", std::exp(se)) : "";
    return "measured: " + fallback + " error " + figure("%.3g", fallback_error / kept_error) +
           "x " + possessive(kept) + uncertain + cost;
}

// Why the verdict went as it did: the screen's share of the light found unblocked, and (where
// one was made) the measured errors.
std::string reason(const nlohmann::json& l) {
    const std::string by = l.value("verdict_by", "none");
    const std::string kept = l.value("verdict_kept", "none");
    std::string screen, measure;
    if (by == "screen")
        screen = "its shadow rays had found " +
                 figure("%.3g", 100.0 * l.value("verdict_screen_share", 0.0)) +
                 "% of their light unblocked at the screen";
    // (The screen can leave a measurement to make: the binned samples against the fallback.)
    if (l.value("verdict_measured", false))
        measure = measured(l, kept);
    if (screen.empty() && measure.empty())
        return "";
    return " (" + screen + (screen.empty() || measure.empty() ? "" : "; then ") + measure + ")";
}

} // namespace

std::string learning_summary(const nlohmann::json& l) {
    if (!l.is_object() || !l.contains("verdict"))
        return "";
    const std::string verdict = l.value("verdict", "none");
    const std::string kept = l.value("verdict_kept", "none");
    std::string s = "learning: ";
    if (verdict == "none") // the render ended first, or there is no verdict (--guide-verdict off)
        s += (kept == "tables" || kept == "none" ? "the learned tables"
                                                 : technique(kept) + " in the tables' place") +
             ", no verdict given";
    else if (verdict == "tables")
        s += "kept the learned tables";
    else
        s += technique(verdict) + " after the learning";
    // The passes learnt in this process (a render that stopped early learnt fewer than the
    // learning's planned end), and their time with the verdict's measuring passes.
    const int passes = l.value("learned_passes", 0);
    const double verdict_seconds = l.value("verdict_seconds", 0.0);
    return s + reason(l) + "; " + std::to_string(passes) +
           (passes == 1 ? " learning pass" : " learning passes") +
           (verdict_seconds > 0.0 ? " and the verdict's: " : ": ") +
           figure("%.2f", l.value("learning_seconds", 0.0) + verdict_seconds) + " s";
}

} // namespace et
