// The CSV dialect of the rig-data format: UTF-8 (BOM tolerated), comma
// separated, '#' comment lines and blank lines ignored, LF or CRLF, a header
// of `name` or `name [unit]` cells, then rows of finite numbers, each with as
// many fields as the header. Units are kept as written; converting them is the
// caller's business (it knows which quantity a column holds).
#pragma once

#include <string>
#include <vector>

namespace pneumaid {

struct CsvColumn {
  std::string name;  // "p1"
  std::string unit;  // "bar_g"; empty when the header gave none
  int column = 0;    // 1-based position in the header
  std::vector<double> values;
};

struct CsvTable {
  std::string file;
  int header_line = 0;
  std::vector<CsvColumn> columns;
  std::vector<int> row_lines;  // the file line of each data row, for messages
  // The last data row is the file's last line and has no line end: a log cut
  // while it was written ends so (its last number may be cut short too). The
  // dialect allows it; `check` says it.
  bool unterminated_last_row = false;

  // nullptr when there is no such column.
  const CsvColumn* Find(const std::string& name) const;
  std::size_t rows() const { return row_lines.size(); }
};

// Parses `text` (the contents of `file`). Throws InputError with file, line
// and column for every violation of the dialect above.
CsvTable ParseCsv(const std::string& text, const std::string& file);

// Reads and parses a file (throws InputError, also when it cannot be opened).
CsvTable ReadCsv(const std::string& path);

}  // namespace pneumaid
