#pragma once
// debrief.html: the session's figures as one self-contained page a trainee and an instructor read
// after a session (no network, no script: the pictures are inline SVG and an embedded PNG). The
// figures beside a reference run's (another session's debrief.json, e.g. an expert's), a timeline
// of the beam, contrast, C-arm moves and force events, the tip's path drawn on the frame that
// showed the vessels best, and the tip's force against time (the rod wire). docs/debrief.md.
#include <nlohmann/json.hpp>
#include <string>

#include "server/debrief/session_metrics.h"

namespace pcisim::server {

// `reference`: another session's debrief.json (nullptr: none); `title` heads the page
std::string debrief_html(const DebriefFigures& f, const nlohmann::json* reference, const std::string& title);

}  // namespace pcisim::server
