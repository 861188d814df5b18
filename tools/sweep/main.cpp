// atmos_sweep: random valid configurations of the renderer and the engine
// plugin, checked for NaN, infinite and negative light (docs/hardening.md).
//
//   atmos_sweep --runs 10000 --seed 1           the sweep
//   atmos_sweep --seed 1 --replay 4711          one run again, with its configuration
#include <CLI/CLI.hpp>

#include <csignal>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <string>

#include <unistd.h>

#include "atmos/renderer.hpp"
#include "sweep.hpp"

namespace {

// The replay command of the run that crashed the process, written with
// async-signal-safe calls only (write, not printf) before the signal's
// default action ends the process.
char g_command_prefix[256];

void write_text(const char* text) {
  const ssize_t ignored = write(STDERR_FILENO, text, std::strlen(text));
  (void)ignored;
}

void on_crash(int signal) {
  const int index = atmos::sweep::current_run_index();
  write_text("\natmos_sweep: crashed (signal ");
  char digits[24];
  int n = 0;
  unsigned v = unsigned(signal);
  do {
    digits[n++] = char('0' + v % 10);
    v /= 10;
  } while (v != 0);
  char out[24];
  for (int i = 0; i < n; ++i) out[i] = digits[n - 1 - i];
  out[n] = '\0';
  write_text(out);
  write_text(")");
  if (index >= 0) {
    write_text(" in run ");
    n = 0;
    unsigned u = unsigned(index);
    do {
      digits[n++] = char('0' + u % 10);
      u /= 10;
    } while (u != 0);
    for (int i = 0; i < n; ++i) out[i] = digits[n - 1 - i];
    out[n] = '\0';
    write_text(out);
    write_text("; replay: ");
    write_text(g_command_prefix);
    write_text(" --replay ");
    write_text(out);
  } else {
    write_text(" while preparing a planet");
  }
  write_text("\n");
  std::signal(signal, SIG_DFL);
  std::raise(signal);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"atmos_sweep: random valid configurations of atmos::Renderer and atmos::AtmospherePass, checked for "
               "NaN, infinite and negative pixels"};
  atmos::sweep::SweepOptions options;
  bool renderer_only = false, plugin_only = false, quiet = false;
  app.add_option("--runs", options.runs, "number of runs")->check(CLI::Range(1, 100000000));
  app.add_option("--seed", options.seed, "seed of the sweep");
  app.add_option("--runs-per-planet", options.runs_per_planet, "consecutive runs that share a planet's tables")
      ->check(CLI::Range(1, 1000000));
  app.add_option("--replay", options.replay, "run only this index (with its planet) and print its configuration")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--first", options.first_run, "start at this run index (resume a sweep: the same --seed, --runs and "
                                              "--runs-per-planet give the same runs)")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--renderer-only", renderer_only, "only atmos::Renderer");
  app.add_flag("--plugin-only", plugin_only, "only atmos::AtmospherePass");
  app.add_flag("--quiet", quiet, "no progress line");
  bool verbose = false;
  app.add_flag("--verbose", verbose, "a line per planet and per run with their times");
  CLI11_PARSE(app, argc, argv);
  if (options.first_run >= options.runs) {
    std::cerr << "atmos_sweep: --first " << options.first_run << " must be below --runs " << options.runs << "\n";
    return 2;
  }
  if (renderer_only && plugin_only) {
    std::cerr << "atmos_sweep: --renderer-only and --plugin-only exclude each other\n";
    return 2;
  }
  options.targets = renderer_only ? atmos::sweep::Targets::renderer_only
                    : plugin_only ? atmos::sweep::Targets::plugin_only
                                  : atmos::sweep::Targets::both;
  const std::string prefix = "atmos_sweep --seed " + std::to_string(options.seed) + " --runs-per-planet " +
                             std::to_string(options.runs_per_planet) +
                             (renderer_only ? " --renderer-only" : plugin_only ? " --plugin-only" : "");
  std::snprintf(g_command_prefix, sizeof g_command_prefix, "%s", prefix.c_str());
  for (int s : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) std::signal(s, on_crash);

  std::unique_ptr<atmos::GlContext> context;
  try {
    context = atmos::GlContext::create_headless();
  } catch (const atmos::Error& e) {
    std::cerr << "atmos_sweep: " << e.what() << "\n";
    return 2;
  }
  if (!quiet && options.replay < 0) {
    options.progress = [](int done, int total, const std::string& status) {
      if (done % 50 != 0 && done != total) return;
      std::fprintf(stderr, "\ratmos_sweep: %d / %d runs%s%s", done, total, status.empty() ? "" : ", ",
                   status.c_str());
      if (done == total) std::fprintf(stderr, "\n");
      std::fflush(stderr);
    };
  }
  if (verbose) options.log = [](const std::string& line) { std::cerr << line << "\n"; };
  std::cout << "atmos_sweep: " << context->renderer_string() << "\n";
  if (options.replay >= 0) {
    const atmos::sweep::PlanetCase planet =
        atmos::sweep::make_planet(options.seed, options.replay / std::max(options.runs_per_planet, 1));
    std::cout << atmos::sweep::describe(planet) << "\n"
              << atmos::sweep::describe(atmos::sweep::make_run(options.seed, options.replay, planet, options.targets))
              << "\n";
  }
  const atmos::sweep::SweepResult result = atmos::sweep::run_sweep(options);
  std::cout << atmos::sweep::summary(result, options);
  for (const atmos::sweep::Failure& f : result.failures)
    std::cout << "\n" << atmos::sweep::describe(f) << "\n  replay: " << prefix << " --replay " << f.index << "\n";
  return result.failures.empty() ? 0 : 1;
}
