#include "markdown.h"

#include <algorithm>
#include <sstream>
#include <vector>

#include "html_page.h"

namespace pneumaid::report_internal {
namespace {

// **bold** and `code` within one line, the rest escaped.
std::string Inline(const std::string& text) {
  std::string out;
  bool bold = false, code = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (!code && text.compare(i, 2, "**") == 0) {
      out += bold ? "</b>" : "<b>";
      bold = !bold;
      ++i;
    } else if (text[i] == '`') {
      out += code ? "</code>" : "<code>";
      code = !code;
    } else {
      out += Html(std::string(1, text[i]));
    }
  }
  if (code) out += "</code>";
  if (bold) out += "</b>";
  return out;
}

// The cells of a table row "| a | b |".
std::vector<std::string> Cells(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  for (std::size_t i = 1; i < line.size(); ++i) {
    if (line[i] == '|') {
      const auto first = cell.find_first_not_of(' ');
      const auto last = cell.find_last_not_of(' ');
      cells.push_back(first == std::string::npos ? "" : cell.substr(first, last - first + 1));
      cell.clear();
    } else {
      cell += line[i];
    }
  }
  return cells;
}

bool IsSeparatorRow(const std::string& line) {
  return line.size() > 1 && line[0] == '|' && line.find_first_not_of("|-: ") == std::string::npos;
}

}  // namespace

std::string MarkdownToHtml(const std::string& markdown) {
  std::istringstream in(markdown);
  std::ostringstream out;
  std::string line;
  enum class Block { kNone, kParagraph, kList, kTable, kCode } block = Block::kNone;
  bool table_header = false;
  const auto close = [&]() {
    if (block == Block::kParagraph) out << "</p>\n";
    if (block == Block::kList) out << "</ul>\n";
    if (block == Block::kTable) out << "</table>\n";
    block = Block::kNone;
  };
  while (std::getline(in, line)) {
    if (block == Block::kCode) {
      if (line.rfind("```", 0) == 0) {
        out << "</pre>\n";
        block = Block::kNone;
      } else {
        out << Html(line) << "\n";
      }
      continue;
    }
    if (line.rfind("```", 0) == 0) {
      close();
      out << "<pre>";
      block = Block::kCode;
    } else if (line.empty()) {
      close();
    } else if (line[0] == '#') {
      close();
      // A bare "#" or "## " is an empty heading.
      const std::size_t level = std::min(line.find_first_not_of('#'), line.size());
      const std::size_t h = std::min<std::size_t>(level + 1, 6);
      const std::size_t text = std::min(line.find_first_not_of(' ', level), line.size());
      out << "<h" << h << ">" << Inline(line.substr(text)) << "</h" << h << ">\n";
    } else if (line[0] == '|') {
      if (IsSeparatorRow(line)) continue;
      if (block != Block::kTable) {
        close();
        out << "<table>\n";
        block = Block::kTable;
        table_header = true;
      }
      const char* cell = table_header ? "th" : "td";
      out << "<tr>";
      for (const std::string& text : Cells(line))
        out << "<" << cell << " class=l>" << Inline(text) << "</" << cell << ">";
      out << "</tr>\n";
      table_header = false;
    } else if (line.rfind("- ", 0) == 0) {
      if (block != Block::kList) {
        close();
        out << "<ul>\n";
        block = Block::kList;
      }
      out << "<li>" << Inline(line.substr(2)) << "</li>\n";
    } else {
      if (block != Block::kParagraph) {
        close();
        out << "<p>";
        block = Block::kParagraph;
      } else {
        out << "\n";
      }
      out << Inline(line);
    }
  }
  if (block == Block::kCode) out << "</pre>\n";
  close();
  return out.str();
}

}  // namespace pneumaid::report_internal
