// atmos — rendered images and their files.
//
// An `Image` holds linear sRGB on the cd/m² scale: the luminance of a pixel is
// atmos::srgb_luminance(rgb) in cd/m² (colour.hpp). EXR files keep those
// values unchanged; PNG files are exposed, tone mapped and sRGB encoded.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace atmos {

struct Image {
  int width = 0;
  int height = 0;
  // width * height * 3 floats, row-major, top row first, R G B interleaved;
  // linear sRGB primaries, scaled so that Y is the luminance in cd/m².
  std::vector<float> rgb;
};

// 32-bit float OpenEXR with channels R, G, B holding the values of `image`
// unchanged (linear sRGB, cd/m² luminance scale), ZIP compressed (lossless).
// Throws atmos::Error (one line naming `path`) if the image holds NaN or
// infinite values, has inconsistent dimensions, or the file cannot be written.
void write_exr(const Image& image, const std::string& path);

// 8-bit sRGB PNG. Each channel L (cd/m²) is exposed and tone mapped as
//   display = 1 - exp(-L / L_sat),  L_sat = 1.2 * 2^exposure_ev,
// where L_sat is the saturation luminance of a camera at exposure value
// `exposure_ev` (EV100; 78 / (100 * 0.65) = 1.2), then clamped to [0, 1] and
// encoded with the sRGB OETF (IEC 61966-2-1). Throws atmos::Error like write_exr.
void write_png(const Image& image, const std::string& path, double exposure_ev);

// Display-referred 8-bit pixels (sRGB-encoded), e.g. from PostProcess
// (post.hpp): width * height * 3 bytes, R G B interleaved, top row first.
struct DisplayImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;
};

// Writes already tone-mapped pixels unchanged as an 8-bit sRGB PNG. Throws
// atmos::Error naming `path` on inconsistent dimensions or a failed write.
void write_png(const DisplayImage& image, const std::string& path);

// write_png or write_exr by the extension of `path` (.png / .exr, any case);
// any other extension throws atmos::Error "unsupported output format ...".
// `exposure_ev` is used by PNG only.
void write_image(const Image& image, const std::string& path, double exposure_ev);

// Reads the R, G, B channels of an OpenEXR file (for tests and tools).
// Throws atmos::Error naming `path` if it cannot be read.
Image read_exr(const std::string& path);

}  // namespace atmos
