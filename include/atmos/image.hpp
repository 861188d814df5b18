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

// Reads the R, G, B channels of an OpenEXR file (for tests and tools).
// Throws atmos::Error naming `path` if it cannot be read.
Image read_exr(const std::string& path);

}  // namespace atmos
