// Measured figures that the documentation quotes (docs/accuracy.md, written
// by scripts/docs.py from a test run, never by hand).
//
// record_figure prints the figure as a readable line on stdout and, when the
// environment variable ATMOS_FIGURES_FILE names a file, appends it there as
// one JSON object per line:
//
//   {"test": "Suite.Name", "name": "...", "value": <number>, "unit": "...", "bound": "..."}
//
// `test` is the running GoogleTest test ("Suite.*" from a suite's set-up),
// `name` says what was measured (unique within the test), `bound` the
// tolerance the test asserts on it, as text.
// A value that is not finite is written as null (JSON has no NaN).
// Call it from the test's own thread, not from inside a parallel loop.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace atmos_test {

// `text` as the contents of a JSON string (quotes, backslashes and control
// characters escaped; UTF-8 passes through).
inline std::string json_escaped(const std::string& text) {
  std::string out;
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += ch;
    } else if (c < 0x20) {
      char buffer[8];
      std::snprintf(buffer, sizeof buffer, "\\u%04x", unsigned(c));
      out += buffer;
    } else {
      out += ch;
    }
  }
  return out;
}

inline void record_figure(const std::string& name, double value, const std::string& unit,
                          const std::string& bound) {
  // Outside a test (in SetUpTestSuite) the figure belongs to the whole suite.
  const ::testing::UnitTest* gtest = ::testing::UnitTest::GetInstance();
  const ::testing::TestInfo* info = gtest->current_test_info();
  const ::testing::TestSuite* suite = gtest->current_test_suite();
  const std::string test = info    ? std::string(info->test_suite_name()) + "." + info->name()
                           : suite ? std::string(suite->name()) + ".*"
                                   : std::string("-");
  std::printf("figure: %s = %.6g%s%s (bound: %s)\n", name.c_str(), value, unit.empty() ? "" : " ", unit.c_str(),
              bound.empty() ? "none" : bound.c_str());
  std::fflush(stdout);

  const char* path = std::getenv("ATMOS_FIGURES_FILE");
  if (path == nullptr || *path == '\0') return;
  char number[40] = "null";
  if (std::isfinite(value)) std::snprintf(number, sizeof number, "%.9g", value);
  const std::string line = "{\"test\": \"" + json_escaped(test) + "\", \"name\": \"" + json_escaped(name) +
                           "\", \"value\": " + number + ", \"unit\": \"" + json_escaped(unit) +
                           "\", \"bound\": \"" + json_escaped(bound) + "\"}\n";
  // One write of the whole line in append mode, so that test processes run
  // one after another (or side by side) do not interleave their lines.
  std::FILE* file = std::fopen(path, "a");
  if (file == nullptr) {
    ADD_FAILURE() << "cannot append to ATMOS_FIGURES_FILE=" << path;
    return;
  }
  const bool written = std::fwrite(line.data(), 1, line.size(), file) == line.size();
  if (std::fclose(file) != 0 || !written) ADD_FAILURE() << "cannot write to ATMOS_FIGURES_FILE=" << path;
}

}  // namespace atmos_test
