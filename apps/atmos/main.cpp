// atmos — command line interface.
//
//   atmos render      render images (no arguments: the default gallery)
//   atmos precompute  build or verify the table cache, with timings
//   atmos sample      radiance for directions read as CSV (tables or --reference)
//   atmos bench       precomputation and render timings, name<TAB>value<TAB>unit
//   atmos plot-data   CSV files for scripts/plots.py (docs/plots.md)
//   atmos view        the interactive viewer (docs/viewer.md)
//
// One file per command (commands.hpp); the options several commands share
// are defined once in options.hpp. Exit codes: 0 success, 1 runtime error
// (bad planet file, no OpenGL, I/O), 2 usage error (unknown command or flag,
// bad value).
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "commands.hpp"

int main(int argc, char** argv) {
  using namespace atmos_cli;
  CLI::App app{"atmos: physically based rendering of planetary atmospheres"};
  app.require_subcommand(1);
  app.set_help_all_flag("--help-all", "Help for all commands");
  const std::vector<Command> commands = {add_render_command(app), add_precompute_command(app),
                                         add_sample_command(app), add_bench_command(app),
                                         add_plot_data_command(app), add_view_command(app)};

  if (argc > 1 && argv[1][0] != '-') {
    const std::string command = argv[1];
    std::string names;
    bool known = false;
    for (size_t i = 0; i < commands.size(); ++i) {
      const std::string& name = commands[i].app->get_name();
      known = known || name == command;
      names += (i == 0 ? "" : i + 1 == commands.size() ? " or " : ", ") + name;
    }
    if (!known) {
      std::fprintf(stderr, "atmos: error: unknown command \"%s\" (expected %s)\n", command.c_str(), names.c_str());
      return 2;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "atmos: error: %s\n", e.what());
    return 2;
  }

  try {
    for (const Command& command : commands)
      if (command.app->parsed()) return command.run();
  } catch (const UsageError& e) {
    std::fprintf(stderr, "atmos: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "atmos: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
