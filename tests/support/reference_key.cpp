#include "support/reference_key.hpp"

#include <cinttypes>
#include <cstdio>

#include "reference_source_hash.hpp"

namespace atmos_test::oracle {

Key::Key(const char* function) { text_ << function << ';' << ATMOS_REFERENCE_SOURCE_HASH << ';'; }

Key& Key::number(double v) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%a,", v);
  text_ << buffer;
  return *this;
}

Key& Key::integer(std::int64_t v) {
  text_ << v << ',';
  return *this;
}

Key& Key::vec(const glm::dvec3& v) { return number(v.x).number(v.y).number(v.z); }

Key& Key::list(const std::vector<double>& values) {
  integer(std::int64_t(values.size()));
  for (double v : values) number(v);
  return *this;
}

Key& Key::spectrum(const atmos::Spectrum& s) { return list(s.wavelengths_nm()).list(s.values()); }

Key& Key::atmosphere(const atmos::Atmosphere& a) {
  list(a.wavelengths_nm).number(a.bottom_radius_m).number(a.top_radius_m).number(a.sun_angular_radius_rad);
  spectrum(a.ground_albedo).spectrum(a.solar_irradiance);
  integer(std::int64_t(a.constituents.size()));
  for (const atmos::Constituent& c : a.constituents) {
    integer(int(c.density.kind)).number(c.density.scale_height_m).integer(std::int64_t(c.density.knots.size()));
    for (const auto& [altitude, density] : c.density.knots) number(altitude).number(density);
    spectrum(c.scattering).spectrum(c.absorption);
    integer(int(c.phase.kind)).spectrum(c.phase.g).spectrum(c.phase.g_back).spectrum(c.phase.forward_weight);
  }
  return *this;
}

Key& Key::options(const atmos::ReferenceOptions& o) {
  integer(o.scattering_orders).integer(o.paths).integer(std::int64_t(o.seed)).number(o.sun_limb_darkening_u);
  integer(std::int64_t(o.moons.size()));
  for (const auto& m : o.moons) vec(m.centre).number(m.radius);
  return *this;
}

std::string Key::hex() const {
  const std::string s = text_.str();
  std::uint64_t a = 0xcbf29ce484222325ull, b = 0x84222325cbf29ce4ull;
  for (unsigned char c : s) {
    a = (a ^ c) * 0x100000001b3ull;
    b = (b ^ c) * 0x100000001b3ull;
  }
  char out[33];
  std::snprintf(out, sizeof out, "%016" PRIx64 "%016" PRIx64, a, b);
  return out;
}

// The references are deterministic, so a change of the compiler, the
// platform or the store's contents shows in every entry it touches: a
// quarter of them finds it at a quarter of the Monte Carlo's time, and a
// quarter fixed by the keys (hashes, uniform in their digits) keeps the full
// tier's run time and outcome the same from run to run.
bool verified_entry(const std::string& key, bool first_of_suite) {
  if (first_of_suite) return true;
  const char last = key.empty() ? '0' : key.back();
  const int digit = last >= 'a' ? last - 'a' + 10 : last - '0';
  return digit % 4 == 0;
}

std::string radiance_key(const atmos::Atmosphere& atmosphere, const glm::dvec3& observer, const glm::dvec3& view,
                         const glm::dvec3& sun, const atmos::ReferenceOptions& options) {
  return Key("reference_radiance").atmosphere(atmosphere).vec(observer).vec(view).vec(sun).options(options).hex();
}

}  // namespace atmos_test::oracle
