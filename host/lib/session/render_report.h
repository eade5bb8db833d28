// The facts of a finished render, described once and written two ways: as the stats JSON
// (`render --stats`) and as the image's metadata (envtrace:* attributes). Each fact names its
// place in each output (or none), so the two cannot drift apart.
#pragma once
#include "opencl/opencl_runtime.h"
#include "session/render_session.h"

#include <nlohmann/json.hpp>

#include <string>
#include <utility>
#include <vector>

namespace et {

struct ReportFact {
    std::string json; // JSON pointer in the stats ("/rays/camera"); "": not in the stats
    std::string exr;  // the image attribute ("envtrace:spp"); "": not in the metadata
    nlohmann::json value;
    // The attribute's text where it is not the value's own (metadata_text).
    std::string exr_text;
};
using RenderReport = std::vector<ReportFact>;

// What the report is made of: the session after run(), its result and how it was built.
struct ReportInputs {
    const RenderSession& session;
    const SessionResult& result;
    const ProgramBuildInfo& build;
    int ranks = 1;
};

// The facts of a render (rank 0's view: the result's sums and counts are every rank's).
RenderReport render_report(const ReportInputs& in);

// The stats JSON: every fact with a JSON place.
nlohmann::json report_json(const RenderReport& report);
// The image metadata: every fact with an attribute, as text (strings as they are, booleans
// "yes" / "no", numbers as std::to_string writes them, unless the fact gives its text).
std::vector<std::pair<std::string, std::string>> report_metadata(const RenderReport& report);

} // namespace et
