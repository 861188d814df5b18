// The keys of the stored reference results (support/reference_store.hpp):
// the canonical text of a call's inputs and of the reference's code, hashed.
// Apart from the store, so that the unit tests of the keys need neither the
// store's JSON nor the reference itself.
#pragma once

#include <glm/vec3.hpp>

#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "reference/reference.hpp"

namespace atmos_test::oracle {

// The canonical text of a call's inputs: every number as a hexadecimal float
// (exact), every list with its length. Names and file paths of the atmosphere
// are left out: they do not change the physics.
class Key {
 public:
  // Starts with the function's name and the hash of the reference's code.
  explicit Key(const char* function);
  Key& number(double v);
  Key& integer(std::int64_t v);
  Key& vec(const glm::dvec3& v);
  Key& list(const std::vector<double>& values);
  Key& spectrum(const atmos::Spectrum& s);
  Key& atmosphere(const atmos::Atmosphere& a);
  Key& options(const atmos::ReferenceOptions& o);

  // 128 bits of two FNV-1a hashes (Fowler, Noll & Vo) with different offset
  // bases: a name for the entry, not a security measure.
  std::string hex() const;

 private:
  std::ostringstream text_;
};

// The key of a reference_radiance call: a hash of the reference's code and of
// every input (not the atmosphere's name or origin). Exposed for the tests of
// the store itself.
std::string radiance_key(const atmos::Atmosphere& atmosphere, const glm::dvec3& observer, const glm::dvec3& view,
                         const glm::dvec3& sun, const atmos::ReferenceOptions& options);

// Whether verify mode recomputes the entry of `key`: the first one a test
// suite asks for in the process (`first_of_suite`), and those whose key ends
// in a hexadecimal digit that is a multiple of 4. Exposed for the tests of
// the store itself.
bool verified_entry(const std::string& key, bool first_of_suite);

}  // namespace atmos_test::oracle
