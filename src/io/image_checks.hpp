// Checks shared by the writers of images (io and post).
#pragma once

#include <string>

#include "atmos/image.hpp"

namespace atmos {

// Throws Error naming `path` unless the image holds width x height x 3 values,
// all finite.
void check_image(const Image& image, const std::string& path);

}  // namespace atmos
