#include "render/learning_summary.h"

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

// Why the verdict went as it did: the screen's share of the light found unblocked, and (where
// one was made) the measured errors against the kept technique's cost per sample.
std::string reason(const nlohmann::json& l) {
    std::string screen, measure;
    if (l.value("verdict_by", "none") == "screen")
        screen = "the shadow rays of its first update found " +
                 figure("%.3g", 100.0 * l.value("verdict_screen_share", 0.0)) +
                 "% of their light unblocked";
    const double kept_error = l.value("verdict_kept_error", 0.0);
    const std::string kept = l.value("verdict_kept", "none");
    if (kept != "none" && kept_error > 0.0)
        measure = "measured: " + possessive(l.value("verdict_fallback", "compensated")) +
                  " error " + figure("%.3g", l.value("verdict_fallback_error", 0.0) / kept_error) +
                  "x " + possessive(kept) + ", against a cost of " +
                  figure("%.3g", l.value("verdict_cost", 1.0)) + "x";
    if (screen.empty() && measure.empty())
        return "";
    return " (" + screen + (screen.empty() || measure.empty() ? "" : "; then ") + measure + ")";
}

} // namespace

std::string learning_summary(const nlohmann::json& l) {
    if (!l.is_object() || !l.contains("verdict"))
        return "";
    const std::string verdict = l.value("verdict", "none");
    std::string s = "learning: ";
    const std::string kept = l.value("verdict_kept", "none");
    if (verdict == "none") // the render ended first, or there is no verdict (--guide-verdict off)
        s += (kept == "none" || kept == "tables" ? "the learned tables"
                                                 : technique(kept) + " in the tables' place") +
             ", no verdict given";
    else if (verdict == "tables")
        s += "kept the learned tables";
    else
        s += technique(verdict) + " after the learning";
    const int passes = l.value("learning_passes", 0);
    return s + reason(l) + "; " + std::to_string(passes) +
           (passes == 1 ? " learning pass, " : " learning passes, ") +
           figure("%.2f", l.value("learning_seconds", 0.0)) + " s";
}

} // namespace et
