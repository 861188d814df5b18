#include "support/reference_store.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>

#include "support/reference_key.hpp"

namespace atmos_test::oracle {
namespace {

using nlohmann::json;

enum class Mode { stored, verify, write, fill };

Mode mode() {
  static const Mode m = [] {
    const char* v = std::getenv("ATMOS_REFERENCE_MODE");
    const std::string s = v != nullptr ? v : "stored";
    if (s == "stored" || s.empty()) return Mode::stored;
    if (s == "verify") return Mode::verify;
    if (s == "write") return Mode::write;
    if (s == "fill") return Mode::fill;
    std::fprintf(stderr, "ATMOS_REFERENCE_MODE must be stored, verify, write or fill, not \"%s\"\n", s.c_str());
    std::abort();
  }();
  return m;
}

std::filesystem::path store_directory() {
  if (const char* dir = std::getenv("ATMOS_REFERENCE_STORE")) return dir;
  return std::filesystem::path(ATMOS_SOURCE_DIR) / "tests" / "data" / "reference";
}

// One file per test suite, loaded once per process and rewritten after each
// new entry in write mode.
class Store {
 public:
  static Store& instance() {
    static Store store;
    return store;
  }

  json lookup_or_compute(const std::string& key, const std::string& description, const std::function<json()>& compute) {
    const std::string suite = suite_name();
    if (mode() == Mode::stored) {
      std::unique_lock lock(mutex_);
      const json& entries = load(suite);
      if (entries.contains(key)) return entries.at(key).at("result");
      // Thrown, not computed: a stale store fails at once rather than after
      // the reference's minutes of computation.
      throw std::runtime_error("no stored reference result for " + description + " (key " + key + ") in " +
                               file(suite).string() +
                               ": the inputs or the reference's code changed; run scripts/update-references.sh");
    }
    if (mode() == Mode::fill) {
      std::lock_guard lock(mutex_);
      const json& entries = load(suite);
      if (entries.contains(key)) return entries.at(key).at("result");
    }
    if (mode() == Mode::verify) {
      std::unique_lock lock(mutex_);
      const bool first_of_suite = verified_suites_.insert(suite).second;
      if (!verified_entry(key, first_of_suite)) {
        const json& entries = load(suite);
        if (entries.contains(key)) return entries.at(key).at("result");
        throw std::runtime_error("no stored reference result for " + description + " (key " + key + ") in " +
                                 file(suite).string() + ": run scripts/update-references.sh");
      }
    }
    const json result = compute();
    std::lock_guard lock(mutex_);
    json& entries = load(suite);
    if (mode() == Mode::verify) {
      if (!entries.contains(key))
        ADD_FAILURE() << "no stored reference result for " << description << " (key " << key << ") in "
                      << file(suite).string() << ": run scripts/update-references.sh";
      else if (entries.at(key).at("result") != result)
        ADD_FAILURE() << "the reference's result for " << description << " differs from the stored one in "
                      << file(suite).string() << ":\n  stored   " << entries.at(key).at("result").dump().substr(0, 400)
                      << "\n  computed " << result.dump().substr(0, 400);
      return result;
    }
    entries[key] = json{{"call", description}, {"result", result}};
    save(suite);
    return result;
  }

 private:
  static std::string suite_name() {
    const ::testing::TestSuite* suite = ::testing::UnitTest::GetInstance()->current_test_suite();
    std::string name = suite != nullptr ? suite->name() : "no_suite";
    for (char& c : name)
      if (c == '/') c = '_';
    return name;
  }
  static std::filesystem::path file(const std::string& suite) { return store_directory() / (suite + ".json"); }

  json& load(const std::string& suite) {
    auto it = suites_.find(suite);
    if (it != suites_.end()) return it->second;
    json entries = json::object();
    std::ifstream in(file(suite));
    if (in) {
      try {
        const json doc = json::parse(in);
        if (doc.value("format", "") != "atmos-reference-store-1")
          ADD_FAILURE() << file(suite).string() << " is not a reference store (format atmos-reference-store-1)";
        else
          entries = doc.at("entries");
      } catch (const json::exception& e) {
        ADD_FAILURE() << "cannot read " << file(suite).string() << ": " << e.what();
      }
    }
    return suites_.emplace(suite, std::move(entries)).first->second;
  }

  void save(const std::string& suite) {
    std::filesystem::create_directories(store_directory());
    const json doc{{"format", "atmos-reference-store-1"},
                   {"note", "generated by scripts/update-references.sh; keys hash the inputs and the reference's code"},
                   {"entries", suites_.at(suite)}};
    const std::filesystem::path path = file(suite), temp = path.string() + ".tmp";
    {
      std::ofstream out(temp, std::ios::trunc);
      out << doc.dump(1) << '\n';
      if (!out) {
        ADD_FAILURE() << "cannot write " << temp.string();
        return;
      }
    }
    std::filesystem::rename(temp, path);
  }

  std::mutex mutex_;
  std::map<std::string, json> suites_;
  std::set<std::string> verified_suites_;  // verify mode: the suites whose first entry has been asked for
};

json finite_list(const std::vector<double>& values, const std::string& what) {
  for (double v : values)
    if (!std::isfinite(v)) ADD_FAILURE() << what << ": the reference returned a non-finite value";
  return json(values);
}

json to_json(const atmos::ReferenceResult& r) {
  return json{{"radiance", finite_list(r.radiance, "radiance")},
              {"standard_error", finite_list(r.standard_error, "standard error")}};
}

atmos::ReferenceResult result_from(const json& j) {
  atmos::ReferenceResult r;
  r.radiance = j.at("radiance").get<std::vector<double>>();
  r.standard_error = j.at("standard_error").get<std::vector<double>>();
  return r;
}

std::string describe(const char* function, const atmos::Atmosphere& a, const glm::dvec3& p, const glm::dvec3& d) {
  char buffer[256];
  std::snprintf(buffer, sizeof buffer, "%s(%s, (%.6g, %.6g, %.6g), (%.4f, %.4f, %.4f))", function, a.name.c_str(), p.x,
                p.y, p.z, d.x, d.y, d.z);
  return buffer;
}

}  // namespace

atmos::ReferenceResult reference_radiance(const atmos::Atmosphere& atmosphere, const glm::dvec3& observer,
                                          const glm::dvec3& view, const glm::dvec3& sun,
                                          const atmos::ReferenceOptions& options) {
  const std::string key = radiance_key(atmosphere, observer, view, sun, options);
  return result_from(Store::instance().lookup_or_compute(
      key, describe("reference_radiance", atmosphere, observer, view),
      [&] { return to_json(atmos::reference_radiance(atmosphere, observer, view, sun, options)); }));
}

atmos::ReferenceResult reference_irradiance(const atmos::Atmosphere& atmosphere, const glm::dvec3& point,
                                            const glm::dvec3& normal, const glm::dvec3& sun,
                                            const atmos::ReferenceOptions& options) {
  const std::string key =
      Key("reference_irradiance").atmosphere(atmosphere).vec(point).vec(normal).vec(sun).options(options).hex();
  return result_from(Store::instance().lookup_or_compute(
      key, describe("reference_irradiance", atmosphere, point, normal),
      [&] { return to_json(atmos::reference_irradiance(atmosphere, point, normal, sun, options)); }));
}

atmos::ReferenceResult reference_horizontal_irradiance(const atmos::Atmosphere& atmosphere, const glm::dvec3& point,
                                                       const glm::dvec3& sun, const atmos::ReferenceOptions& options) {
  const std::string key =
      Key("reference_horizontal_irradiance").atmosphere(atmosphere).vec(point).vec(sun).options(options).hex();
  return result_from(Store::instance().lookup_or_compute(
      key, describe("reference_horizontal_irradiance", atmosphere, point, sun),
      [&] { return to_json(atmos::reference_horizontal_irradiance(atmosphere, point, sun, options)); }));
}

atmos::ReferenceResult reference_radiance_to_point(const atmos::Atmosphere& atmosphere, const glm::dvec3& observer,
                                                   const glm::dvec3& point, const glm::dvec3& sun,
                                                   const atmos::ReferenceOptions& options) {
  const std::string key =
      Key("reference_radiance_to_point").atmosphere(atmosphere).vec(observer).vec(point).vec(sun).options(options).hex();
  return result_from(Store::instance().lookup_or_compute(
      key, describe("reference_radiance_to_point", atmosphere, observer, point),
      [&] { return to_json(atmos::reference_radiance_to_point(atmosphere, observer, point, sun, options)); }));
}

std::vector<double> reference_transmittance(const atmos::Atmosphere& atmosphere, const glm::dvec3& from,
                                            const glm::dvec3& to) {
  const std::string key = Key("reference_transmittance").atmosphere(atmosphere).vec(from).vec(to).hex();
  return Store::instance()
      .lookup_or_compute(key, describe("reference_transmittance", atmosphere, from, to),
                         [&] { return finite_list(atmos::reference_transmittance(atmosphere, from, to), "transmittance"); })
      .get<std::vector<double>>();
}

atmos::PlaneParallelFluxes reference_plane_parallel_fluxes(const atmos::Atmosphere& atmosphere, double mu_s,
                                                           const atmos::PlaneParallelOptions& options) {
  const std::string key = Key("reference_plane_parallel_fluxes")
                              .atmosphere(atmosphere)
                              .number(mu_s)
                              .integer(options.streams)
                              .number(options.max_layer_optical_depth)
                              .number(options.max_layer_thickness_m)
                              .hex();
  char description[160];
  std::snprintf(description, sizeof description, "reference_plane_parallel_fluxes(%s, mu_s %.6g)",
                atmosphere.name.c_str(), mu_s);
  const json j = Store::instance().lookup_or_compute(key, description, [&] {
    const atmos::PlaneParallelFluxes f = atmos::reference_plane_parallel_fluxes(atmosphere, mu_s, options);
    return json{{"upward_top", finite_list(f.upward_top, "upward flux")},
                {"ground_direct", finite_list(f.ground_direct, "direct flux")},
                {"ground_diffuse", finite_list(f.ground_diffuse, "diffuse flux")},
                {"mu", f.mu},
                {"upward_radiance_top", f.upward_radiance_top},
                {"downward_radiance_ground", f.downward_radiance_ground}};
  });
  atmos::PlaneParallelFluxes f;
  f.upward_top = j.at("upward_top").get<std::vector<double>>();
  f.ground_direct = j.at("ground_direct").get<std::vector<double>>();
  f.ground_diffuse = j.at("ground_diffuse").get<std::vector<double>>();
  f.mu = j.at("mu").get<std::vector<double>>();
  f.upward_radiance_top = j.at("upward_radiance_top").get<std::vector<std::vector<double>>>();
  f.downward_radiance_ground = j.at("downward_radiance_ground").get<std::vector<std::vector<double>>>();
  return f;
}

}  // namespace atmos_test::oracle
