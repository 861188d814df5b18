// What the table-cache fuzz target and its seed writer share: the tables the
// cache files are decoded against, and the byte layout of a file's key and
// checksum (src/precompute/cache.cpp writes them).
#pragma once

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "atmos/planet_file.hpp"
#include "atmos/tables.hpp"

namespace atmos::fuzz {

// Tables of the smallest sizes TableSizes::validate() accepts: a whole cache
// file is then about 5 kB, so that every mutation reaches its end.
inline TableSizes tiny_sizes() { return TableSizes{4, 4, 4, 2, 2, 4, 8, 2}; }

// A planet and precomputation options whose cache files the fuzzer decodes.
struct CacheConfig {
  std::string name;
  Atmosphere atmosphere;
  PrecomputeOptions options;
  std::string key;  // tables_cache_key(atmosphere, options)
};

// Two configurations that together reach every part of a file:
//  - earth-3: three working wavelengths (one triple), 2 fixed orders (one
//    convergence entry);
//  - earth-6-auto: six wavelengths (two triples, two transmittance tiles each),
//    auto orders capped at 2, so the tail is solved and the convergence
//    report ends with a tail entry.
inline std::vector<CacheConfig> cache_configs() {
  std::vector<CacheConfig> configs;
  CacheConfig three{"earth-3", load_atmosphere("earth"), {}, ""};
  three.options.sizes = tiny_sizes();
  three.options.scattering_orders = 2;
  configs.push_back(three);
  CacheConfig six{"earth-6-auto", load_atmosphere("earth"), {}, ""};
  six.atmosphere.wavelengths_nm = spectral_wavelengths(6);
  six.options.sizes = tiny_sizes();
  six.options.scattering_orders = 2;
  six.options.auto_orders = true;
  configs.push_back(six);
  for (CacheConfig& c : configs) c.key = tables_cache_key(c.atmosphere, c.options);
  return configs;
}

// The file layout: 8 bytes of magic, a 4-byte version, the 16 hex digits of
// the key, ..., and last the 64-bit FNV-1a hash (Fowler, Noll & Vo) of all the
// bytes before it.
constexpr std::size_t kKeyOffset = 12;
constexpr std::size_t kKeyBytes = 16;
constexpr std::size_t kChecksumBytes = 8;

inline std::uint64_t fnv1a(const unsigned char* p, std::size_t n) {
  std::uint64_t h = 1469598103934665603ull;
  for (std::size_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 1099511628211ull;
  }
  return h;
}

// `file` with the key of `key` and a checksum that matches its other bytes:
// a mutated file that gets past the key and checksum checks, so that the
// fuzzer reaches the decoding behind them. Files too short to hold a key and
// a checksum come back unchanged.
inline std::string with_key_and_checksum(std::string file, const std::string& key) {
  if (file.size() < kKeyOffset + kKeyBytes + kChecksumBytes || key.size() != kKeyBytes) return file;
  std::memcpy(file.data() + kKeyOffset, key.data(), kKeyBytes);
  const std::size_t body = file.size() - kChecksumBytes;
  const std::uint64_t h = fnv1a(reinterpret_cast<const unsigned char*>(file.data()), body);
  std::memcpy(file.data() + body, &h, kChecksumBytes);
  return file;
}

}  // namespace atmos::fuzz
