#include "pneumaid/io/csv_table.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <set>
#include <string_view>

#include "parse_number.h"
#include "pneumaid/io/files.h"
#include "pneumaid/io/input_error.h"

namespace pneumaid {
namespace {

std::string_view Trim(std::string_view text) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t' || text.back() == '\r')) {
    text.remove_suffix(1);
  }
  return text;
}

bool IsSkipped(std::string_view line) {
  const std::string_view content = Trim(line);
  return content.empty() || content.front() == '#';
}

// Walks the text line by line, counting lines from 1.
class LineCursor {
 public:
  explicit LineCursor(std::string_view text) : text_(text) {
    if (text_.substr(0, 3) == "\xEF\xBB\xBF") text_.remove_prefix(3);  // UTF-8 BOM
  }

  bool Next(std::string_view* line) {
    if (position_ >= text_.size()) return false;
    const std::size_t end = text_.find('\n', position_);
    const std::size_t stop = end == std::string_view::npos ? text_.size() : end;
    *line = text_.substr(position_, stop - position_);
    if (!line->empty() && line->back() == '\r') line->remove_suffix(1);
    position_ = stop + 1;
    ++number_;
    return true;
  }

  int number() const { return number_; }

 private:
  std::string_view text_;
  std::size_t position_ = 0;
  int number_ = 0;
};

class CsvParser {
 public:
  explicit CsvParser(std::string file) { table_.file = std::move(file); }

  CsvTable Parse(std::string_view text) {
    if (text.empty()) Fail(0, 0, "empty file: expected a header line and data rows");
    CheckEncoding(text);
    LineCursor cursor(text);
    std::string_view line;
    bool last_line_is_row = false;
    while (cursor.Next(&line)) {
      last_line_is_row = false;
      if (IsSkipped(line)) continue;
      if (table_.header_line == 0) {
        table_.header_line = cursor.number();
        ParseHeader(line);
      } else {
        ParseRow(line, cursor.number());
        last_line_is_row = true;
      }
    }
    if (last_line_is_row && text.back() != '\n') table_.unterminated_last_row = true;
    if (table_.header_line == 0) Fail(0, 0, "no header line: expected e.g. 't [s],u [V],...'");
    if (table_.rows() == 0) Fail(table_.header_line, 0, "header with no data rows");
    return std::move(table_);
  }

 private:
  // What the dialect is not, said as such: UTF-16 (a spreadsheet's "Unicode
  // text") and old Mac line ends (CR alone) otherwise fail later, in their
  // first cell or as "no header line".
  void CheckEncoding(std::string_view text) const {
    if (text.substr(0, 2) == "\xFF\xFE" || text.substr(0, 2) == "\xFE\xFF") {
      Fail(1, 0, "a UTF-16 byte-order mark: expected UTF-8 text (save the log as UTF-8 CSV)");
    }
    const std::size_t nul = text.find('\0');
    if (nul != std::string_view::npos) {
      const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + nul, '\n'));
      Fail(line, 0, "a NUL byte: expected UTF-8 text (is the log UTF-16?)");
    }
    const std::size_t first_break = text.find_first_of("\r\n");
    if (first_break != std::string_view::npos && text[first_break] == '\r' &&
        (first_break + 1 == text.size() || text[first_break + 1] != '\n') &&
        text.find('\r', first_break + 1) != std::string_view::npos) {
      Fail(1, 0, "lines end in CR alone: expected LF or CRLF line ends");
    }
  }

  [[noreturn]] void Fail(int line, int column, const std::string& message) const {
    throw InputError(table_.file, line, column, message);
  }

  void ParseHeader(std::string_view line) {
    if (line.find(',') == std::string_view::npos) {
      for (const char separator : {';', '\t'}) {
        if (line.find(separator) != std::string_view::npos) {
          Fail(table_.header_line, 0,
               std::string("header separated by ") + (separator == ';' ? "';'" : "tabs") +
                   ": expected comma-separated cells with a decimal point, e.g. 't [s],u [V],x "
                   "[mm]'");
        }
      }
    }
    std::set<std::string> seen;
    int column = 0;
    std::size_t start = 0;
    while (true) {
      const std::size_t comma = line.find(',', start);
      const std::string_view cell = Trim(line.substr(start, comma - start));
      ++column;
      CsvColumn parsed = ParseHeaderCell(cell, column);
      if (!seen.insert(parsed.name).second) {
        Fail(table_.header_line, column, "duplicate column '" + parsed.name + "'");
      }
      table_.columns.push_back(std::move(parsed));
      if (comma == std::string_view::npos) break;
      start = comma + 1;
    }
  }

  CsvColumn ParseHeaderCell(std::string_view cell, int column) const {
    CsvColumn out;
    out.column = column;
    const std::size_t open = cell.find('[');
    if (open == std::string_view::npos) {
      out.name = std::string(cell);
    } else {
      if (cell.back() != ']') {
        Fail(table_.header_line, column,
             "header cell '" + std::string(cell) + "': expected 'name' or 'name [unit]'");
      }
      out.name = std::string(Trim(cell.substr(0, open)));
      out.unit = std::string(Trim(cell.substr(open + 1, cell.size() - open - 2)));
      if (out.unit.empty()) Fail(table_.header_line, column, "empty unit brackets");
    }
    if (out.name.empty()) Fail(table_.header_line, column, "empty column name in header");
    return out;
  }

  void ParseRow(std::string_view line, int line_number) {
    const std::size_t expected = table_.columns.size();
    std::size_t start = 0;
    for (std::size_t column = 0; column < expected; ++column) {
      const std::size_t comma = line.find(',', start);
      const bool last = column + 1 == expected;
      if (comma == std::string_view::npos && !last) {
        Fail(line_number, 0,
             "ragged row: " + std::to_string(column + 1) + " fields, expected " +
                 std::to_string(expected) + " as in the header");
      }
      if (comma != std::string_view::npos && last) {
        Fail(line_number, 0,
             "ragged row: more than the " + std::to_string(expected) + " fields of the header");
      }
      const std::string_view field = Trim(line.substr(start, comma - start));
      table_.columns[column].values.push_back(ParseNumber(field, line_number, column + 1));
      start = comma + 1;
    }
    table_.row_lines.push_back(line_number);
  }

  double ParseNumber(std::string_view field, int line, std::size_t column) const {
    double value = 0;
    const char* end = field.data() + field.size();
    if (internal::ParseNumber(field.data(), end, &value) != end || !std::isfinite(value)) {
      Fail(line, static_cast<int>(column),
           "column '" + table_.columns[column - 1].name + "': expected a finite number, got '" +
               std::string(field) + "'");
    }
    return value;
  }

  CsvTable table_;
};

}  // namespace

const CsvColumn* CsvTable::Find(const std::string& name) const {
  for (const auto& column : columns) {
    if (column.name == name) return &column;
  }
  return nullptr;
}

CsvTable ParseCsv(const std::string& text, const std::string& file) {
  return CsvParser(file).Parse(text);
}

CsvTable ReadCsv(const std::string& path) { return ParseCsv(ReadTextFile(path, "CSV file"), path); }

}  // namespace pneumaid
