// The pieces every report page is built from (internal to src/report/): text
// escaped for HTML, plots as data for the page's script (report_page.h), the
// min/max decimation of long runs, and the page itself: a body written
// section by section, its plots collected, then one self-contained document
// with the vendored uPlot, the style and the data inlined.
#pragma once

#include <sstream>
#include <string>
#include <vector>

namespace pneumaid::report_internal {

// `text` with <, >, & and " escaped.
std::string Html(const std::string& text);

// printf into a std::string (display numbers only: the page's data go
// through to_chars).
std::string Printf(const char* format, ...) __attribute__((format(printf, 1, 2)));

struct Series {
  std::string label, color;
  std::vector<double> values;  // one per x; NaN: a gap
  int axis = 1;                // 2: the right-hand axis
  bool points = false;         // markers only, no line
};

struct Plot {
  std::string title;
  std::string group;  // plots of one group share their x scale and cursor
  std::string x_label, y_label, y2_label;
  std::vector<double> x;
  std::vector<Series> series;
};

// Min/max per column: `columns` buckets of the samples, each giving two
// points (its extremes of every series, the earlier first), so spikes stay.
void Decimate(int columns, Plot* plot);

class HtmlPage {
 public:
  // Long runs are decimated to `max_columns` columns when added.
  HtmlPage(std::string title, int max_columns);

  // The body, written in order; text must already be escaped.
  std::ostringstream& body() { return body_; }

  // Writes the plot's placeholder into the body (decimated) and keeps its data.
  void AddPlot(Plot plot);
  int plots() const { return static_cast<int>(plots_.size()); }

  // The whole document: the status element the page's self-check writes
  // into heads the body.
  std::string Finish() const;

 private:
  std::string title_;
  int max_columns_;
  std::ostringstream body_;
  std::vector<Plot> plots_;
};

}  // namespace pneumaid::report_internal
