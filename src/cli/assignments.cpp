#include <algorithm>
#include <ctime>
#include <filesystem>

#include "../io/parse_number.h"
#include "commands.h"
#include "pneumaid/io/input_error.h"

namespace pneumaid::cli {

std::map<std::string, double> ParseAssignments(
    const std::vector<std::string>& items, const std::string& option, const std::string& expected,
    const std::function<bool(const std::string&)>& key_allowed) {
  std::map<std::string, double> out;
  for (const auto& item : items) {
    const auto eq = item.find('=');
    double value = 0;
    const char* const stop = item.c_str() + item.size();
    // Locale-independent, as every reader of pneumaid.
    const char* end = eq == std::string::npos
                          ? nullptr
                          : internal::ParseNumber(item.c_str() + eq + 1, stop, &value);
    const std::string key = item.substr(0, eq);
    if (eq == 0 || end == nullptr || end != stop || end == item.c_str() + eq + 1 ||
        (key_allowed && !key_allowed(key))) {
      throw InputError(option, 0, 0, "'" + item + "': expected " + expected);
    }
    out[key] = value;
  }
  return out;
}

void ThrowNamingTheFlag(const std::string& message,
                        const std::vector<std::pair<std::string, std::string>>& flags) {
  for (const auto& [field, flag] : flags) {
    if (message.compare(0, field.size(), field) == 0)
      throw InputError(flag, 0, 0, message.substr(field.size()));
  }
}

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> items;
  std::size_t begin = 0;
  while (begin <= text.size()) {
    const std::size_t end = std::min(text.find(',', begin), text.size());
    if (end > begin) items.push_back(text.substr(begin, end - begin));
    begin = end + 1;
  }
  return items;
}

std::string UtcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);  // thread-safe, unlike std::gmtime
  char text[32];
  std::strftime(text, sizeof(text), "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

std::string DefaultConfig(const std::string& name) {
  std::error_code error;
  const std::filesystem::path binary = std::filesystem::read_symlink("/proc/self/exe", error);
  if (!error) {
    const std::filesystem::path installed =
        binary.parent_path().parent_path() / PNEUMAID_INSTALLED_CONFIGS / name;
    if (std::filesystem::exists(installed, error)) return installed.string();
  }
  return std::string(PNEUMAID_SOURCE_CONFIGS) + "/" + name;
}

}  // namespace pneumaid::cli
