// The fixture of the GPU test suites: one headless OpenGL context and one
// set of small Earth tables (table_sizes.hpp) per suite. ctest runs each
// test in its own process, and the small tables take about a second.
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "atmos/atmosphere.hpp"
#include "atmos/planet_file.hpp"
#include "atmos/renderer.hpp"
#include "atmos/tables.hpp"
#include "table_sizes.hpp"

namespace atmos_test {

class EarthGpuTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    earth_ = std::make_unique<atmos::Atmosphere>(atmos::load_atmosphere("earth"));
    atmos::PrecomputeOptions options;
    options.sizes = small_gpu_sizes();
    tables_ = std::make_unique<atmos::Tables>(atmos::precompute_tables(*earth_, options));
    try {
      context_ = atmos::GlContext::create_headless();
    } catch (const atmos::Error& e) {
      error_ = e.what();
    }
  }
  static void TearDownTestSuite() {
    context_.reset();
    tables_.reset();
    earth_.reset();
  }
  void SetUp() override {
    // A failure, not a skip: the GL path must be tested wherever the tests run.
    ASSERT_TRUE(context_ != nullptr) << error_;
  }

  static inline std::unique_ptr<atmos::Atmosphere> earth_;
  static inline std::unique_ptr<atmos::Tables> tables_;
  static inline std::unique_ptr<atmos::GlContext> context_;
  static inline std::string error_;
};

// Earth with other values and the same structure (the same programs): a
// longer Rayleigh scale height, another ground albedo, sun and top radius.
inline atmos::Atmosphere other_earth_values(const atmos::Atmosphere& earth) {
  atmos::Atmosphere other = earth;
  other.constituents[0].density.scale_height_m *= 1.2;
  other.ground_albedo = atmos::Spectrum::constant(0.31);
  other.sun_angular_radius_rad *= 1.1;
  other.top_radius_m += 5e3;
  return other;
}

}  // namespace atmos_test
