// The one error type for problems in user input (files, command lines). It
// names the file, the line and column where known (0 = not applicable), and
// what was expected. The CLI maps it to exit status 2.
#pragma once

#include <stdexcept>
#include <string>

namespace pneumaid {

class InputError : public std::runtime_error {
 public:
  InputError(std::string file, int line, int column, std::string message);

  const std::string& file() const { return file_; }
  int line() const { return line_; }
  int column() const { return column_; }
  const std::string& message() const { return message_; }

 private:
  std::string file_;
  int line_;
  int column_;
  std::string message_;
};

}  // namespace pneumaid
