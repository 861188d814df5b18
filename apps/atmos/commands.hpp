// The subcommands of `atmos`, one file each (render.cpp, precompute.cpp,
// sample.cpp, bench.cpp, plot_data.cpp, view.cpp). Each adds itself to the
// application with its options and returns what runs it.
#pragma once

#include <CLI/CLI.hpp>

#include "options.hpp"

namespace atmos_cli {

Command add_render_command(CLI::App& app);
Command add_precompute_command(CLI::App& app);
Command add_sample_command(CLI::App& app);
Command add_bench_command(CLI::App& app);
Command add_plot_data_command(CLI::App& app);
Command add_view_command(CLI::App& app);

}  // namespace atmos_cli
