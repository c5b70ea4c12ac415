// The text reports' Markdown as HTML (internal to src/report/), so that a
// page shows exactly the tables and evidence of the Markdown report it
// accompanies instead of a second copy of them: headings (one level down),
// tables, lists, fenced code, paragraphs, **bold** and `code`. Nothing else
// of Markdown is needed by pneumaid's own reports; any other text passes
// through escaped.
#pragma once

#include <string>

namespace pneumaid::report_internal {

std::string MarkdownToHtml(const std::string& markdown);

}  // namespace pneumaid::report_internal
