// atmos bench: the view.* lines, the interactive viewer timed as a user
// starts it (atmos view in a window, under xvfb-run without a display).
#pragma once

#include <functional>
#include <string>

#include "harness.hpp"

namespace atmos_cli {

// Runs `atmos view` (this executable) four times at 1280x720 for
// `planet` and hands over:
//  - view.sphere.median_frame, view.globe.median_frame (ms) and their
//    frames per second: the viewer's median frame over the analytic sphere
//    and over the terrain globe (its tiles complete, the panel shown);
//  - view.stereo.globe.anaglyph.median_frame (ms) and its frames per
//    second: the same over the globe in red-cyan stereo (--stereo anaglyph);
//  - view.first_frame.cold_shader_cache (s): from the viewer's start to its
//    first frame of the planet with Mesa's shader cache disabled
//    (MESA_SHADER_CACHE_DISABLE), the tables already cached, the globe's
//    tiles streamed as in an interactive session.
// Without a display and without xvfb-run, or without the viewer, prints
// why on stderr and hands over nothing.
void view_bench(const std::string& planet, const std::function<void(const atmos_bench::Figure&)>& sink);

}  // namespace atmos_cli
