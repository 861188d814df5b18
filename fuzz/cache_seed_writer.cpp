// Writes the seed corpus of cache_file_fuzzer into a directory: for each
// configuration of cache_fuzz_support.hpp, a real cache file (computed with
// the tiny table sizes through load_or_precompute_tables) and variants that
// each break one check of the decoder: truncations, a flipped byte, another
// magic or version, header fields claiming huge or negative counts, another
// working wavelength, a non-finite convergence entry or texel (all but the
// first three with a repaired checksum, so that the decoder sees the field
// and not the checksum). The files are named *.bin:
// the repository ignores *.tables, the name of real cache files.
//
//   cache_seed_writer <directory>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

#include "cache_fuzz_support.hpp"

namespace {

namespace fs = std::filesystem;

// Field offsets of the header (src/precompute/cache.cpp, write_cache).
constexpr std::size_t kVersionOffset = 8;
constexpr std::size_t kSizesOffset = 28;         // 8 x int32
constexpr std::size_t kSetsOffset = 64;          // int32
constexpr std::size_t kWavelengthsOffset = 68;   // int32
constexpr std::size_t kConvergenceOffset = 72;   // int32
constexpr std::size_t kHeaderBytes = 76;

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

void write(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), std::streamsize(bytes.size()));
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

void put_i32(std::string& file, std::size_t offset, std::int32_t v) { std::memcpy(file.data() + offset, &v, 4); }

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s <directory>\n", argv[0]);
    return 2;
  }
  try {
    const fs::path out = argv[1];
    fs::create_directories(out);
    const fs::path scratch = fs::temp_directory_path() / ("atmos-cache-seeds-" + std::to_string(::getpid()));
    for (const atmos::fuzz::CacheConfig& c : atmos::fuzz::cache_configs()) {
      const atmos::CacheResult computed = atmos::load_or_precompute_tables(c.atmosphere, c.options, scratch.string());
      const std::string real = slurp(computed.path);
      if (real.size() <= kHeaderBytes) throw std::runtime_error("the cache file of " + c.name + " was not written");
      auto repaired = [&](std::string f) { return atmos::fuzz::with_key_and_checksum(std::move(f), c.key); };
      const fs::path base = out / c.name;
      write(base.string() + ".bin", real);
      write(base.string() + "-header-only.bin", real.substr(0, kHeaderBytes));
      write(base.string() + "-truncated.bin", real.substr(0, real.size() - 100));
      std::string flipped = real;
      flipped[flipped.size() / 2] = char(flipped[flipped.size() / 2] ^ 0x5a);
      write(base.string() + "-flipped-byte.bin", flipped);
      std::string magic = real;
      magic[0] = 'X';
      write(base.string() + "-magic.bin", repaired(magic));
      std::string version = real;
      version[kVersionOffset] = char(version[kVersionOffset] + 1);
      write(base.string() + "-version.bin", repaired(version));
      std::string huge_sizes = real;
      for (int i = 0; i < 8; ++i) put_i32(huge_sizes, kSizesOffset + 4 * std::size_t(i), 4096);
      write(base.string() + "-huge-sizes.bin", repaired(huge_sizes));
      std::string huge_counts = real;
      put_i32(huge_counts, kSetsOffset, std::numeric_limits<std::int32_t>::max());
      put_i32(huge_counts, kWavelengthsOffset, std::numeric_limits<std::int32_t>::max());
      put_i32(huge_counts, kConvergenceOffset, std::numeric_limits<std::int32_t>::max());
      write(base.string() + "-huge-counts.bin", repaired(huge_counts));
      std::string negative_counts = real;
      put_i32(negative_counts, kSetsOffset, -1);
      put_i32(negative_counts, kWavelengthsOffset, -1);
      put_i32(negative_counts, kConvergenceOffset, -1);
      write(base.string() + "-negative-counts.bin", repaired(negative_counts));
      std::string wavelength = real;
      const double other_wavelength = c.atmosphere.wavelengths_nm[0] + 1.0;
      std::memcpy(wavelength.data() + kHeaderBytes, &other_wavelength, 8);
      write(base.string() + "-other-wavelength.bin", repaired(wavelength));
      std::string nan_convergence = real;
      const double nan_sum = std::numeric_limits<double>::quiet_NaN();
      // The first entry's `added`, after the wavelengths, its order and its iterations.
      std::memcpy(nan_convergence.data() + kHeaderBytes + 8 * c.atmosphere.wavelengths_nm.size() + 8, &nan_sum, 8);
      write(base.string() + "-nan-convergence.bin", repaired(nan_convergence));
      std::string nan_texel = real;
      const float nan = std::numeric_limits<float>::quiet_NaN();
      std::memcpy(nan_texel.data() + nan_texel.size() - 8 - 4, &nan, 4);
      write(base.string() + "-nan-texel.bin", repaired(nan_texel));
    }
    fs::remove_all(scratch);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cache_seed_writer: %s\n", e.what());
    return 1;
  }
  return 0;
}
