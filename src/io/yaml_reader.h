// What every YAML reader of pneumaid shares: the source name for messages,
// syntax errors and non-scalar keys turned into InputError at their line and
// column, and a guard that converts any other yaml-cpp exception the same way
// (a malformed document must never escape as anything but InputError).
#pragma once

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <set>
#include <string>
#include <vector>

#include "parse_number.h"
#include "pneumaid/io/input_error.h"

namespace pneumaid::internal {

// "a, b, c": names as a message lists them.
inline std::string JoinNames(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& name : names) out += (out.empty() ? "" : ", ") + name;
  return out;
}

class YamlReader {
 protected:
  explicit YamlReader(std::string source) : source_(std::move(source)) {}

  // Parses `text`; a document that is not a mapping fails with `expected`.
  YAML::Node LoadMapping(const std::string& text, const std::string& expected) const {
    std::vector<YAML::Node> documents;
    try {
      documents = YAML::LoadAll(text);
    } catch (const YAML::Exception& error) {
      throw InputError(source_, error.mark.line + 1, error.mark.column + 1,
                       "YAML syntax error: " + error.msg);
    }
    // A second document (two files run together after '---') would be
    // dropped unread.
    for (std::size_t i = 1; i < documents.size(); ++i) {
      if (!documents[i].IsNull()) {  // a trailing '---' opens an empty one: nothing dropped
        Fail(documents[i], "a second YAML document: expected one (two files joined?)");
      }
    }
    const YAML::Node root = documents.empty() ? YAML::Node() : documents.front();
    if (!root.IsMap()) Fail(root, expected);
    NoDuplicateKeys(root);
    return root;
  }

  // A mapping that names a key twice is ambiguous (yaml-cpp keeps both: a
  // lookup finds the first, a walk ends at the last): bad input, at the
  // second.
  void NoDuplicateKeys(const YAML::Node& node) const {
    if (node.IsMap()) {
      std::set<std::string> seen;
      for (const auto& entry : node) {
        if (entry.first.IsScalar() && !seen.insert(entry.first.Scalar()).second)
          Fail(entry.first, "duplicate key '" + entry.first.Scalar() + "'");
        NoDuplicateKeys(entry.second);
      }
    } else if (node.IsSequence()) {
      for (const auto& item : node) NoDuplicateKeys(item);
    }
  }

  [[noreturn]] void Fail(const YAML::Node& node, const std::string& message) const {
    const YAML::Mark mark = node.Mark();
    throw InputError(source_, mark.line >= 0 ? mark.line + 1 : 0,
                     mark.column >= 0 ? mark.column + 1 : 0, message);
  }

  // A mapping key as text; a key that is itself a list or mapping fails.
  std::string Key(const YAML::Node& key) const {
    if (!key.IsScalar()) Fail(key, "expected a plain key");
    return key.Scalar();
  }

  std::string Scalar(const YAML::Node& node, const std::string& path) const {
    if (!node.IsScalar()) Fail(node, path + ": expected a scalar value");
    return node.Scalar();
  }

  std::string Text(const YAML::Node& node) const { return Scalar(node, "value"); }

  double Number(const YAML::Node& node, const std::string& path) const {
    const std::string text = Text(node);
    const char* end = text.c_str() + text.size();
    double value = 0;
    if (ParseNumber(text.c_str(), end, &value) != end || !std::isfinite(value)) {
      Fail(node, path + ": expected a finite number in SI units");
    }
    return value;
  }

  // Strictly positive.
  double Positive(const YAML::Node& node, const std::string& path) const {
    const double value = Number(node, path);
    if (!(value > 0)) Fail(node, path + ": expected > 0");
    return value;
  }

  // A whole number in [lowest, highest] (|highest| at most 2^53, exact in a
  // double); `fallback` when the key is absent.
  long long Whole(const YAML::Node& node, const std::string& path, double lowest, double highest,
                  long long fallback) const {
    if (!node) return fallback;
    const double value = Number(node, path);
    if (value != std::floor(value) || value < lowest || value > highest) {
      Fail(node, path + ": expected a whole number from " +
                     std::to_string(static_cast<long long>(lowest)) + " to " +
                     std::to_string(static_cast<long long>(highest)));
    }
    return static_cast<long long>(value);
  }

  // Whole() for an int: highest at most INT_MAX.
  int Count(const YAML::Node& node, const std::string& path, double lowest, double highest,
            int fallback) const {
    return static_cast<int>(
        Whole(node, path, lowest, std::min<double>(highest, INT_MAX), fallback));
  }

  bool Flag(const YAML::Node& node) const {
    const std::string text = Text(node);
    if (text != "true" && text != "false") Fail(node, "expected true | false");
    return text == "true";
  }

  std::vector<double> List(const YAML::Node& node, const std::string& path) const {
    if (!node || !node.IsSequence() || node.size() == 0) {
      Fail(node ? node : YAML::Node(), path + ": expected a non-empty list of numbers");
    }
    std::vector<double> out;
    for (const auto& item : node) out.push_back(Positive(item, path));
    return out;
  }

  // Fails on the first key of `node` not in `allowed`, naming it with `prefix`
  // and listing the keys expected there. A key with nothing after it fails too
  // (NotEmpty), unless `empty_allowed` (a set of names, `channels: {x, p1}`,
  // where a bare key means "with the defaults").
  void Keys(const YAML::Node& node, const std::string& prefix, const std::set<std::string>& allowed,
            bool empty_allowed = false) const {
    if (!node.IsMap()) {
      std::string where = prefix.empty() ? "the document" : prefix;
      if (where.back() == '.') where.pop_back();
      Fail(node, where + ": expected a mapping");
    }
    for (const auto& entry : node) {
      const std::string key = Key(entry.first);
      if (!allowed.count(key)) {
        Fail(entry.first, "unknown key '" + prefix + key + "' (expected " +
                              JoinNames({allowed.begin(), allowed.end()}) + ")");
      }
      if (!empty_allowed) NotEmpty(entry.first, entry.second, prefix + key);
    }
  }

  // A key with nothing after it (`sensors:`) is refused at the key's line: a
  // null value's mark is the next token's, often the next key's line.
  void NotEmpty(const YAML::Node& key, const YAML::Node& value, const std::string& path) const {
    if (value.IsNull()) {
      Fail(key, path + ": expected a value after the key, got none (an empty mapping is {})");
    }
  }

  // Runs `read`, turning any yaml-cpp exception into an InputError.
  template <typename Read>
  auto Guarded(const Read& read) const -> decltype(read()) {
    try {
      return read();
    } catch (const YAML::Exception& error) {
      throw InputError(source_, error.mark.line + 1, error.mark.column + 1, error.msg);
    }
  }

  std::string source_;
};

}  // namespace pneumaid::internal
