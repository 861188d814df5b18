// The table cache file's decoder, apart from the file system: what
// load_or_precompute_tables applies to the bytes of a cache file, and what the
// fuzz target (fuzz/cache_file_fuzzer.cpp) feeds with arbitrary bytes.
#pragma once

#include <string>
#include <string_view>

#include "atmos/tables.hpp"

namespace atmos {

// Checks the bytes of a cache file against the tables that `atmosphere` and
// `options` would give (magic, format version, `key`, table sizes, orders,
// wavelengths, length, checksum) and decodes them into `tables`. Returns an
// empty string on success, else a one-line reason the file is unusable; then
// `tables` holds nothing to use. Nothing is allocated before the length of
// `bytes` has been checked against the sizes the options require.
std::string read_tables_file(std::string_view bytes, const std::string& key, const PrecomputeOptions& options,
                             const Atmosphere& atmosphere, Tables& tables);

}  // namespace atmos
