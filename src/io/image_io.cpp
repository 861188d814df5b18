// EXR and PNG output of rendered images.
//
// Both encoders write into memory and this file writes the bytes, so that
// every failure to write becomes one atmos::Error naming the path and the
// system's reason, whatever the encoder's own error reporting.
#include <tinyexr.h>

// stb_image_write is compiled here, with internal linkage (STATIC) so that it
// cannot clash with another translation unit that includes it too. Its code
// is not written for this project's warning flags.
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wconversion"
#pragma GCC diagnostic ignored "-Wsign-conversion"
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#include <stb_image_write.h>
#pragma GCC diagnostic pop

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "atmos/image.hpp"
#include "io/image_checks.hpp"

namespace atmos {

// Dimensions consistent with the pixel data, and every value finite: a NaN
// or an infinity in a picture is always a bug upstream, never data.
void check_image(const Image& image, const std::string& path) {
  if (image.width < 1 || image.height < 1 ||
      image.rgb.size() != size_t(image.width) * size_t(image.height) * 3)
    throw Error("cannot write " + path + ": image of " + std::to_string(image.width) + "x" +
                std::to_string(image.height) + " pixels holds " + std::to_string(image.rgb.size()) + " values");
  for (size_t i = 0; i < image.rgb.size(); ++i) {
    if (!std::isfinite(image.rgb[i])) {
      const size_t pixel = i / 3;
      throw Error("cannot write " + path + ": pixel (" + std::to_string(pixel % size_t(image.width)) + ", " +
                  std::to_string(pixel / size_t(image.width)) + ") is " + (std::isnan(image.rgb[i]) ? "NaN" : "infinite"));
    }
  }
}

namespace {

void write_file(const std::string& path, const unsigned char* data, size_t size) {
  errno = 0;
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  if (!file) throw Error("cannot write " + path + ": " + (errno != 0 ? std::strerror(errno) : "cannot open"));
  file.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  file.close();
  if (!file) {
    const std::string reason = errno != 0 ? std::strerror(errno) : "write failed";
    std::error_code ignored;
    std::filesystem::remove(path, ignored);  // no truncated image left behind (e.g. disk full)
    throw Error("cannot write " + path + ": " + reason);
  }
}

// tinyexr's messages may end in a newline; keep one line.
std::string exr_message(const char* message) {
  std::string s = message != nullptr ? message : "unknown error";
  FreeEXRErrorMessage(message);
  std::replace(s.begin(), s.end(), '\n', ' ');
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

void encode_png(int width, int height, const std::vector<unsigned char>& pixels, const std::string& path) {
  std::vector<unsigned char> encoded;
  auto append = [](void* context, void* data, int size) {
    auto* out = static_cast<std::vector<unsigned char>*>(context);
    const auto* bytes = static_cast<const unsigned char*>(data);
    out->insert(out->end(), bytes, bytes + size);
  };
  if (stbi_write_png_to_func(append, &encoded, width, height, 3, pixels.data(), width * 3) == 0)
    throw Error("cannot write " + path + ": PNG encoding failed");
  write_file(path, encoded.data(), encoded.size());
}

}  // namespace

void write_exr(const Image& image, const std::string& path) {
  check_image(image, path);
  const size_t n = size_t(image.width) * size_t(image.height);
  // EXR stores channels as separate planes, conventionally in B, G, R order.
  std::vector<float> planes[3];
  for (auto& plane : planes) plane.resize(n);
  for (size_t i = 0; i < n; ++i) {
    planes[0][i] = image.rgb[3 * i + 2];
    planes[1][i] = image.rgb[3 * i + 1];
    planes[2][i] = image.rgb[3 * i + 0];
  }
  float* plane_pointers[3] = {planes[0].data(), planes[1].data(), planes[2].data()};

  EXRImage exr_image;
  InitEXRImage(&exr_image);
  exr_image.num_channels = 3;
  exr_image.width = image.width;
  exr_image.height = image.height;
  exr_image.images = reinterpret_cast<unsigned char**>(plane_pointers);

  EXRChannelInfo channels[3];
  std::memset(channels, 0, sizeof channels);
  std::strcpy(channels[0].name, "B");
  std::strcpy(channels[1].name, "G");
  std::strcpy(channels[2].name, "R");
  int pixel_types[3] = {TINYEXR_PIXELTYPE_FLOAT, TINYEXR_PIXELTYPE_FLOAT, TINYEXR_PIXELTYPE_FLOAT};
  int requested_pixel_types[3] = {TINYEXR_PIXELTYPE_FLOAT, TINYEXR_PIXELTYPE_FLOAT, TINYEXR_PIXELTYPE_FLOAT};

  EXRHeader header;
  InitEXRHeader(&header);
  header.num_channels = 3;
  header.channels = channels;
  header.pixel_types = pixel_types;
  header.requested_pixel_types = requested_pixel_types;
  header.compression_type = TINYEXR_COMPRESSIONTYPE_ZIP;  // lossless

  unsigned char* memory = nullptr;
  const char* error = nullptr;
  const size_t size = SaveEXRImageToMemory(&exr_image, &header, &memory, &error);
  if (size == 0 || memory == nullptr) throw Error("cannot write " + path + ": " + exr_message(error));
  try {
    write_file(path, memory, size);
  } catch (...) {
    std::free(memory);
    throw;
  }
  std::free(memory);
}

void write_png(const DisplayImage& image, const std::string& path) {
  if (image.width < 1 || image.height < 1 ||
      image.rgb.size() != size_t(image.width) * size_t(image.height) * 3)
    throw Error("cannot write " + path + ": display image of " + std::to_string(image.width) + "x" +
                std::to_string(image.height) + " pixels holds " + std::to_string(image.rgb.size()) + " bytes");
  encode_png(image.width, image.height, image.rgb, path);
}

Image read_exr(const std::string& path) {
  float* rgba = nullptr;
  int width = 0;
  int height = 0;
  const char* error = nullptr;
  if (LoadEXR(&rgba, &width, &height, path.c_str(), &error) != TINYEXR_SUCCESS)
    throw Error("cannot read " + path + ": " + exr_message(error));
  Image image;
  image.width = width;
  image.height = height;
  const size_t n = size_t(width) * size_t(height);
  image.rgb.resize(n * 3);
  for (size_t i = 0; i < n; ++i)
    for (size_t c = 0; c < 3; ++c) image.rgb[3 * i + c] = rgba[4 * i + c];
  std::free(rgba);
  return image;
}

}  // namespace atmos
