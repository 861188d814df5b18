// The terrain globe's internal switches (src/planet/globe.cpp), for tests:
// not part of the public API (include/atmos/globe.hpp).
#pragma once

namespace atmos::planet {

// With `enabled` false, every Globe draws its tiles unmorphed (the morph
// factor k = 0: each level's own mesh and normals until the selection
// hands its area to another level), i.e. a quadtree level of detail
// without Strugar's (2009) geomorphing, whose level changes pop. For tests
// that measure what the morph hides. Process-wide; morphing is on unless
// switched off here.
void set_globe_morph(bool enabled);

}  // namespace atmos::planet
