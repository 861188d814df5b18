// libFuzzer target: the table cache's decoder (atmos::read_tables_file,
// src/precompute/cache_file.hpp) on arbitrary bytes.
//
// Each input is decoded against the tables of every configuration of
// cache_fuzz_support.hpp twice: as it is, and with the configuration's key
// and a matching checksum written into it (a mutation of a real file almost
// never keeps its checksum, so without the repair nothing behind the checksum
// would be reached). The decoder must refuse a bad file with a one-line
// reason, or return tables that match the planet and hold only finite
// numbers. Anything else (an exception, a crash, a sanitizer report, an
// allocation above libFuzzer's -malloc_limit_mb, a hang) is a finding: this
// target aborts with the reason, and libFuzzer saves the input.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <typeinfo>

#include "cache_fuzz_support.hpp"
#include "precompute/cache_file.hpp"

namespace {

[[noreturn]] void finding(const std::string& config, const std::string& what) {
  std::fprintf(stderr, "cache_file_fuzzer (%s): %s\n", config.c_str(), what.c_str());
  std::abort();
}

void check_texels(const std::string& config, const std::vector<glm::vec3>& texels, const char* table) {
  for (const glm::vec3& t : texels)
    if (!std::isfinite(t.x) || !std::isfinite(t.y) || !std::isfinite(t.z))
      finding(config, std::string("accepted tables with a non-finite texel in ") + table);
}

// What an accepted file promises: tables for this planet and these options,
// of the sizes they say, with finite texels and a finite convergence report.
void check_accepted(const atmos::fuzz::CacheConfig& c, const atmos::Tables& tables) {
  try {
    atmos::check_tables_match(c.atmosphere, tables);
  } catch (const atmos::Error& e) {
    finding(c.name, std::string("accepted tables that do not match the planet: ") + e.what());
  }
  if (!(tables.sizes == c.options.sizes)) finding(c.name, "accepted tables of other sizes");
  const bool orders_ok = c.options.auto_orders
                             ? tables.scattering_orders >= 1 && tables.scattering_orders <= c.options.scattering_orders
                             : tables.scattering_orders == c.options.scattering_orders;
  if (!orders_ok) finding(c.name, "accepted tables of other orders: " + std::to_string(tables.scattering_orders));
  const atmos::TableSet& set = tables.set;
  check_texels(c.name, set.direct_irradiance, "direct_irradiance");
  check_texels(c.name, set.indirect_irradiance, "indirect_irradiance");
  check_texels(c.name, set.scattering, "scattering");
  check_texels(c.name, set.single_aerosol, "single_aerosol");
  check_texels(c.name, set.multiple_scattering, "multiple_scattering");
  check_texels(c.name, tables.spectral_optical_depth, "spectral_optical_depth");
  for (const atmos::OrderContribution& o : tables.convergence)
    if (!std::isfinite(o.added) || !std::isfinite(o.relative) || !std::isfinite(o.residual))
      finding(c.name, "accepted a convergence report with a non-finite number");
}

void decode(const atmos::fuzz::CacheConfig& c, const std::string& bytes) {
  atmos::Tables tables;
  std::string problem;
  try {
    problem = atmos::read_tables_file(bytes, c.key, c.options, c.atmosphere, tables);
  } catch (const std::exception& e) {
    finding(c.name, std::string("the decoder threw ") + typeid(e).name() + ": " + e.what());
  } catch (...) {
    finding(c.name, "the decoder threw something that is not a std::exception");
  }
  if (problem.empty()) {
    check_accepted(c, tables);
  } else if (problem.find('\n') != std::string::npos) {
    finding(c.name, "a reason of several lines: " + problem);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::vector<atmos::fuzz::CacheConfig> configs = atmos::fuzz::cache_configs();
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  for (const atmos::fuzz::CacheConfig& c : configs) {
    decode(c, bytes);
    decode(c, atmos::fuzz::with_key_and_checksum(bytes, c.key));
  }
  return 0;
}
