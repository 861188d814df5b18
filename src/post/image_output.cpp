// HDR images to files: EXR keeps the values, PNG is exposed and tone mapped
// on the CPU with the exp operator of PostProcess (the same definition,
// post/tone_mapping.glsl).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>

#include "atmos/atmosphere.hpp"
#include "atmos/image.hpp"
#include "atmos/post.hpp"
#include "io/image_checks.hpp"
#include "post/tone_mapping_cpp.hpp"

namespace atmos {

namespace {

std::string lowercase_extension(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

}  // namespace

void write_png(const Image& image, const std::string& path, double exposure_ev) {
  check_image(image, path);
  if (!std::isfinite(exposure_ev)) throw Error("cannot write " + path + ": exposure is not finite");
  // x = L / L_sat, display = 1 - exp(-x), sRGB encoded. Negative components
  // (colours outside the sRGB gamut) clamp to black.
  const float exposure = post::exposure_from_ev100(float(exposure_ev));
  DisplayImage display{image.width, image.height, std::vector<std::uint8_t>(image.rgb.size())};
  for (size_t i = 0; i < image.rgb.size(); ++i) {
    const float value = post::display_encoded_channel(image.rgb[i] * exposure, post::TONE_MAP_EXP);
    display.rgb[i] = static_cast<std::uint8_t>(std::lround(value * 255.0f));
  }
  write_png(display, path);
}

void write_image(const Image& image, const std::string& path, double exposure_ev) {
  const std::string ext = lowercase_extension(path);
  if (ext == ".png") return write_png(image, path, exposure_ev);
  if (ext == ".exr") return write_exr(image, path);
  throw Error("unsupported output format " + (ext.empty() ? std::string("(no extension)") : "'" + ext + "'") +
              " for " + path + " (use .png or .exr)");
}

}  // namespace atmos
