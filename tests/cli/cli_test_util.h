// A fixture that runs the `pneumaid` binary in a fresh temporary directory
// and captures its exit status, stdout and stderr.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

namespace pneumaid::testing {

// A path in the source tree (configs, datasets).
inline std::string Source(const std::string& relative) {
  return std::string(PNEUMAID_SOURCE_DIR) + "/" + relative;
}

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // Suite and test name: ctest runs tests of different suites in parallel.
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::path(::testing::TempDir()) /
           ("pneumaid_cli_" + std::string(info->test_suite_name()) + "_" + info->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // Runs `pneumaid <arguments>`; returns its exit status.
  int Run(const std::string& arguments) {
    const std::string command = std::string(PNEUMAID_CLI) + " " + arguments + " > " +
                                (dir_ / "stdout.txt").string() + " 2> " +
                                (dir_ / "stderr.txt").string();
    const int status = std::system(command.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

  std::string Stdout() const { return Read(dir_ / "stdout.txt"); }
  std::string Stderr() const { return Read(dir_ / "stderr.txt"); }

  std::string Write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name, std::ios::binary) << text;
    return (dir_ / name).string();
  }

  static std::string Read(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }

  // Every path below `root`, to check that a failed command wrote nothing.
  static std::set<std::string> Listing(const std::filesystem::path& root) {
    std::set<std::string> names;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(root)) {
      const std::string name = entry.path().filename().string();
      if (name != "stdout.txt" && name != "stderr.txt") names.insert(entry.path().string());
    }
    return names;
  }

  std::filesystem::path dir_;
};

}  // namespace pneumaid::testing
