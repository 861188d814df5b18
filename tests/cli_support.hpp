// Running the `atmos` executable from tests (cli_test.cpp, plot_test.cpp).
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

namespace atmos_test {

namespace fs = std::filesystem;

struct CliRun {
  int code = -1;  // exit code, -1 if the process did not exit normally
  std::string out;
  std::string err;
};

// A directory of this test process for `tag` (created once, removed with
// everything in it when the process exits: ctest runs every test in its own
// process, and each left one behind in the temporary directory).
inline fs::path scratch_directory(const std::string& tag) {
  struct Directories {
    std::set<fs::path> paths;
    ~Directories() {
      for (const fs::path& p : paths) {
        std::error_code ignored;
        fs::remove_all(p, ignored);
      }
    }
  };
  static Directories directories;
  const fs::path d = fs::temp_directory_path() / ("atmos-" + tag + "-test-" + std::to_string(::getpid()));
  fs::create_directories(d);
  directories.paths.insert(d);
  return d;
}

inline std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Runs the CLI (ATMOS_CLI) in `dir` with its own table cache there, `args`
// as they would be typed, `stdin_text` on standard input and `environment`
// ("NAME=value ...") added to its environment.
inline CliRun run_cli(const fs::path& dir, const std::string& args, const std::string& stdin_text = "",
                      const std::string& environment = "") {
  const fs::path out = dir / "stdout.txt", err = dir / "stderr.txt", in = dir / "stdin.txt";
  {
    std::ofstream f(in);
    f << stdin_text;
  }
  const std::string command = "cd '" + dir.string() + "' && ATMOS_CACHE_DIR='" + (dir / "cache").string() + "' " +
                              environment + " '" + ATMOS_CLI + "' " + args + " < '" + in.string() + "' > '" +
                              out.string() + "' 2> '" + err.string() + "'";
  const int status = std::system(command.c_str());
  CliRun r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

}  // namespace atmos_test
