// The keys of the stored reference results (support/reference_key.hpp):
// every input that changes the reference's result changes the key, and
// nothing else does, so a stored result is never used for other inputs.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>

#include "atmos/planet_file.hpp"
#include "support/reference_key.hpp"

namespace {

using atmos_test::oracle::radiance_key;

TEST(ReferenceStore, EveryInputChangesTheKey) {
  const atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  const glm::dvec3 observer(0.0, 0.0, earth.bottom_radius_m + 2.0), view(0.0, 0.6, 0.8), sun(0.0, 0.0, 1.0);
  const atmos::ReferenceOptions options;
  const std::string base = radiance_key(earth, observer, view, sun, options);
  EXPECT_EQ(base.size(), 32u);
  EXPECT_EQ(base, radiance_key(earth, observer, view, sun, options));

  // The name and the origin are not physics.
  atmos::Atmosphere renamed = earth;
  renamed.name = "another name";
  renamed.origin = "/some/other/path.json";
  EXPECT_EQ(base, radiance_key(renamed, observer, view, sun, options));

  std::set<std::string> keys{base};
  auto expect_new = [&](const std::string& key, const char* what) {
    EXPECT_TRUE(keys.insert(key).second) << what << " does not change the key";
  };
  atmos::Atmosphere a = earth;
  a.bottom_radius_m += 1e-6;
  expect_new(radiance_key(a, observer, view, sun, options), "the bottom radius");
  a = earth;
  a.ground_albedo = a.ground_albedo.scaled(1.0 + 1e-15);
  expect_new(radiance_key(a, observer, view, sun, options), "the ground albedo");
  a = earth;
  a.constituents[0].density.scale_height_m *= 1.000001;
  expect_new(radiance_key(a, observer, view, sun, options), "a scale height");
  a = earth;
  for (atmos::Constituent& c : a.constituents)
    if (c.phase.kind != atmos::PhaseFunction::Kind::rayleigh) c.phase.g = c.phase.g.scaled(0.5);
  expect_new(radiance_key(a, observer, view, sun, options), "a phase function");
  a = earth;
  a.constituents.pop_back();
  expect_new(radiance_key(a, observer, view, sun, options), "a constituent");
  expect_new(radiance_key(earth, observer + glm::dvec3(0.0, 0.0, 1e-9), view, sun, options), "the observer");
  expect_new(radiance_key(earth, observer, glm::dvec3(0.0, 0.8, 0.6), sun, options), "the view");
  expect_new(radiance_key(earth, observer, view, glm::dvec3(0.0, 0.6, 0.8), options), "the sun");
  atmos::ReferenceOptions o = options;
  o.paths += 1;
  expect_new(radiance_key(earth, observer, view, sun, o), "the number of paths");
  o = options;
  o.seed += 1;
  expect_new(radiance_key(earth, observer, view, sun, o), "the seed");
  o = options;
  o.scattering_orders += 1;
  expect_new(radiance_key(earth, observer, view, sun, o), "the orders");
  o = options;
  o.moons.push_back({glm::dvec3(0.0, 0.0, 4e8), 1.7e6});
  expect_new(radiance_key(earth, observer, view, sun, o), "a moon");
  o = options;
  o.sun_limb_darkening_u = 0.6;
  expect_new(radiance_key(earth, observer, view, sun, o), "the limb darkening");
}

// Verify mode recomputes the first entry of each suite and a quarter of the
// others, chosen by the key alone.
TEST(ReferenceStore, VerifyModeRecomputesAFixedQuarterOfTheEntries) {
  using atmos_test::oracle::verified_entry;
  const atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  const glm::dvec3 observer(0.0, 0.0, earth.bottom_radius_m + 2.0), sun(0.0, 0.0, 1.0);
  int verified = 0;
  const int keys = 2000;
  for (int i = 0; i < keys; ++i) {
    const double elevation = -1.5 + 3.0 * i / keys;
    const glm::dvec3 view(0.0, std::cos(elevation), std::sin(elevation));
    const std::string key = radiance_key(earth, observer, view, sun, atmos::ReferenceOptions{});
    EXPECT_TRUE(verified_entry(key, true));
    EXPECT_EQ(verified_entry(key, false), verified_entry(key, false));
    verified += verified_entry(key, false) ? 1 : 0;
  }
  EXPECT_GT(verified, keys / 5);
  EXPECT_LT(verified, keys * 3 / 10);
  EXPECT_TRUE(verified_entry("0123456789abcdef0123456789abcdec", false));
  EXPECT_FALSE(verified_entry("0123456789abcdef0123456789abcded", false));
}

}  // namespace
