#include "html_page.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdarg>
#include <cstdio>

#include "pneumaid/io/json.h"
#include "report_page.h"
#include "uplot_assets.h"  // generated from src/report/vendor/uplot by CMake

namespace pneumaid::report_internal {
namespace {

// Numbers for the page's data: 6 significant digits, null for gaps.
void Numbers(std::ostringstream* out, const std::vector<double>& values) {
  *out << "[";
  char text[32];
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (i) *out << ",";
    if (!std::isfinite(values[i])) {
      *out << "null";
      continue;
    }
    const auto end =
        std::to_chars(text, text + sizeof(text), values[i], std::chars_format::general, 6);
    out->write(text, end.ptr - text);
  }
  *out << "]";
}

void PlotJson(const Plot& p, int index, std::ostringstream* out) {
  *out << "{\"id\":\"plot" << index << "\",\"title\":" << JsonString(p.title)
       << ",\"group\":" << (p.group.empty() ? "null" : JsonString(p.group))
       << ",\"x_label\":" << JsonString(p.x_label) << ",\"y_label\":" << JsonString(p.y_label)
       << ",\"y2_label\":" << JsonString(p.y2_label) << ",\"x\":";
  Numbers(out, p.x);
  *out << ",\"series\":[";
  for (std::size_t s = 0; s < p.series.size(); ++s) {
    const Series& series = p.series[s];
    *out << (s ? "," : "") << "{\"label\":" << JsonString(series.label)
         << ",\"color\":" << JsonString(series.color) << ",\"axis\":" << series.axis
         << ",\"points\":" << (series.points ? "true" : "false") << ",\"values\":";
    Numbers(out, series.values);
    *out << "}";
  }
  *out << "]}";
}

}  // namespace

std::string Html(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '<')
      out += "&lt;";
    else if (c == '>')
      out += "&gt;";
    else if (c == '&')
      out += "&amp;";
    else if (c == '"')
      out += "&quot;";
    else
      out += c;
  }
  return out;
}

std::string Printf(const char* format, ...) {
  char text[512];
  va_list args;
  va_start(args, format);
  std::vsnprintf(text, sizeof(text), format, args);
  va_end(args);
  return text;
}

void Decimate(int columns, Plot* plot) {
  const std::size_t n = plot->x.size();
  if (columns <= 0 || n <= static_cast<std::size_t>(2 * columns)) return;
  std::vector<double> x;
  std::vector<std::vector<double>> values(plot->series.size());
  for (int b = 0; b < columns; ++b) {
    const std::size_t begin = n * b / columns, end = n * (b + 1) / columns;
    if (end <= begin) continue;
    x.push_back(plot->x[begin]);
    x.push_back(plot->x[end - 1]);
    for (std::size_t s = 0; s < plot->series.size(); ++s) {
      const auto& v = plot->series[s].values;
      std::size_t lo = begin, hi = begin;
      for (std::size_t i = begin; i < end; ++i) {
        if (v[i] < v[lo] || std::isnan(v[lo])) lo = i;
        if (v[i] > v[hi] || std::isnan(v[hi])) hi = i;
      }
      values[s].push_back(v[std::min(lo, hi)]);
      values[s].push_back(v[std::max(lo, hi)]);
    }
  }
  plot->x = x;
  for (std::size_t s = 0; s < plot->series.size(); ++s) plot->series[s].values = values[s];
}

HtmlPage::HtmlPage(std::string title, int max_columns)
    : title_(std::move(title)), max_columns_(max_columns) {
  body_ << "<h1>" << Html(title_) << "</h1>\n<div id=\"pneumaid-status\">checking</div>\n";
}

void HtmlPage::AddPlot(Plot plot) {
  Decimate(max_columns_, &plot);
  body_ << "<div id=\"plot" << plots_.size() << "\"></div>";
  plots_.push_back(std::move(plot));
}

std::string HtmlPage::Finish() const {
  std::ostringstream data;
  data << "var PNEUMAID_DATA = {\"plots\":[";
  for (std::size_t k = 0; k < plots_.size(); ++k) {
    if (k) data << ",\n";
    PlotJson(plots_[k], static_cast<int>(k), &data);
  }
  data << "]};\n";
  std::ostringstream page;
  page << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>"
       << Html(title_) << "</title>\n<style>" << kUplotCss << kPageStyle << "</style>\n<script>"
       << kUplotJs << "</script>\n</head><body>\n"
       << body_.str() << "<p class=note>Plots: uPlot " << kUplotVersion
       << " (MIT licence, embedded). Long runs are shown with the minimum and maximum of each "
          "of "
       << max_columns_ << " columns.</p>\n<script>" << data.str() << kPageScript
       << "</script>\n</body></html>\n";
  return page.str();
}

}  // namespace pneumaid::report_internal
