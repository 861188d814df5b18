// The post-processing chain's shared functions on the CPU (the same code
// the shaders run: src/post/tone_mapping_cpp.hpp): the tone-mapping curves
// against hand computations from the seed formulas, exposure adaptation,
// the bloom's Gaussian weights and the settings' names. The GPU passes and
// the CLI flags are tested in post_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <iterator>

#include "atmos/atmosphere.hpp"
#include "atmos/post.hpp"
#include "post/tone_mapping_cpp.hpp"

namespace {

namespace post = atmos::post;
using atmos::ToneMapping;

const int kOperators[] = {post::TONE_MAP_EXP, post::TONE_MAP_REINHARD, post::TONE_MAP_FILMIC, post::TONE_MAP_ACES,
                          post::TONE_MAP_LINEAR};
const ToneMapping kToneMappings[] = {ToneMapping::exp, ToneMapping::reinhard, ToneMapping::filmic, ToneMapping::aces,
                                     ToneMapping::linear};

// --- The curves on the CPU (the same code the shaders run) ----------------

TEST(PostToneMap, ZeroMapsToZero) {
  for (int op : kOperators) {
    EXPECT_EQ(post::tone_map_channel(0.0f, op), 0.0f) << op;
    EXPECT_EQ(post::display_encoded_channel(0.0f, op), 0.0f) << op;
    EXPECT_EQ(post::display_linear_channel(0.0f, op), 0.0f) << op;
    // Negative components (out of the sRGB gamut) are black, not negative.
    EXPECT_EQ(post::display_encoded_channel(-3.0f, op), 0.0f) << op;
  }
}

// Non-decreasing over 1e-5 .. 1e4 (exposed units, 200 samples per decade).
// The one exception is documented in tone_mapping.glsl: Collienne 2013's
// Reinhard variant steps down by 3.4e-5 where eq. 4.25 hands over to eq. 4.26.
TEST(PostToneMap, Monotonic) {
  for (int op : kOperators) {
    float previous = 0.0f;
    for (int i = 0; i <= 1800; ++i) {
      const float x = std::pow(10.0f, -5.0f + float(i) / 200.0f);
      const float y = post::tone_map_channel(x, op);
      const float encoded = post::display_encoded_channel(x, op);
      if (op == post::TONE_MAP_REINHARD && previous > y) {
        EXPECT_LT(previous - y, 4e-5f) << "x " << x;
        EXPECT_NEAR(x, post::REINHARD_SWITCH, 0.02f) << "only at the switch between eq. 4.25 and 4.26";
      } else {
        EXPECT_GE(y, previous) << "operator " << op << " x " << x;
      }
      EXPECT_GE(encoded, 0.0f);
      EXPECT_LE(encoded, 1.0f);
      previous = y;
    }
  }
}

// As documented in post.hpp: exp, reinhard and filmic tend to 1 from below,
// aces reaches 1 at x = 7.2417 (root of 0.08 x² - 0.56 x - 0.14 = 0), linear
// is unbounded (clamped only in 8-bit output).
TEST(PostToneMap, SaturatesAsDocumented) {
  for (int op : {post::TONE_MAP_EXP, post::TONE_MAP_REINHARD, post::TONE_MAP_FILMIC}) {
    EXPECT_LT(post::tone_map_channel(1e3f, op), 1.0f + 1e-7f) << op;
    EXPECT_GT(post::tone_map_channel(1e3f, op), 0.9998f) << op;  // filmic: 6200500 / 6201700.06 = 0.999806
  }
  EXPECT_LT(post::tone_map_channel(10.0f, post::TONE_MAP_FILMIC), 1.0f);
  EXPECT_LT(post::tone_map_channel(7.2f, post::TONE_MAP_ACES), 1.0f);
  EXPECT_EQ(post::tone_map_channel(7.3f, post::TONE_MAP_ACES), 1.0f);
  EXPECT_EQ(post::tone_map_channel(1e6f, post::TONE_MAP_ACES), 1.0f);
  EXPECT_EQ(post::tone_map_channel(5.0f, post::TONE_MAP_LINEAR), 5.0f);
  EXPECT_NEAR(post::display_encoded_channel(5.0f, post::TONE_MAP_LINEAR), 1.0f, 1e-7f);
}

TEST(PostToneMap, SeedFormulasReproduceHandComputedValues) {
  // exp (Boody n.d., §1.11): 1 - e^-1 = 0.6321206; sRGB-encoded:
  // 1.055 * 0.6321206^(1/2.4) - 0.055 = 0.8164700.
  EXPECT_NEAR(post::tone_map_channel(1.0f, post::TONE_MAP_EXP), 0.6321206f, 1e-6f);
  EXPECT_NEAR(post::display_encoded_channel(1.0f, post::TONE_MAP_EXP), 0.8164700f, 2e-6f);
  // Reinhard (Collienne 2013, eq. 4.25), x = 1 < 1.413: 0.38317^(1/2.2) = 0.6465952;
  // x = 0.5: (0.5 * 0.38317)^(1/2.2) = 0.4718464.
  EXPECT_NEAR(post::tone_map_channel(1.0f, post::TONE_MAP_REINHARD), 0.6465952f, 2e-6f);
  EXPECT_NEAR(post::tone_map_channel(0.5f, post::TONE_MAP_REINHARD), 0.4718464f, 2e-6f);
  // eq. 4.26, x = 2 >= 1.413: 1 - e^-2 = 0.8646647. Encoded as is (the gamma
  // is in the formula), so display_encoded is the same number.
  EXPECT_NEAR(post::tone_map_channel(2.0f, post::TONE_MAP_REINHARD), 0.8646647f, 1e-6f);
  EXPECT_NEAR(post::display_encoded_channel(2.0f, post::TONE_MAP_REINHARD), 0.8646647f, 1e-6f);
  // Filmic (Collienne 2013, eq. 4.29), x = 1: 1 (6.2 + 0.5) / (1 (6.2 + 1.7) + 0.06) =
  // 6.7 / 7.96 = 0.8417085; x = 0.1: 0.1 * 1.12 / (0.1 * 2.32 + 0.06) =
  // 0.112 / 0.292 = 0.3835616. Its display-linear value is the 2.2 power.
  EXPECT_NEAR(post::tone_map_channel(1.0f, post::TONE_MAP_FILMIC), 0.8417085f, 1e-6f);
  EXPECT_NEAR(post::tone_map_channel(0.1f, post::TONE_MAP_FILMIC), 0.3835616f, 1e-6f);
  EXPECT_NEAR(post::display_linear_channel(1.0f, post::TONE_MAP_FILMIC), std::pow(0.8417085f, 2.2f), 2e-6f);
  // ACES (Narkowicz 2016), x = 1: 2.54 / 3.16 = 0.8037975 ("1 maps to ~0.8");
  // x = 0.18: 0.18 * 0.4818 / (0.18 * 1.0274 + 0.14) = 0.086724 / 0.324932 = 0.2668989.
  EXPECT_NEAR(post::tone_map_channel(1.0f, post::TONE_MAP_ACES), 0.8037975f, 1e-6f);
  EXPECT_NEAR(post::tone_map_channel(0.18f, post::TONE_MAP_ACES), 0.2668989f, 1e-6f);
  // Exposure: EV 0 -> L_sat = 1.2 cd/m²; EV 13 -> 1.2 * 8192 = 9830.4 cd/m².
  EXPECT_NEAR(post::exposure_from_ev100(0.0f), 1.0f / 1.2f, 1e-7f);
  EXPECT_NEAR(1.0f / post::exposure_from_ev100(13.0f), 9830.4f, 1e-2f);
  EXPECT_NEAR(post::ev100_from_exposure(post::exposure_from_ev100(7.25f)), 7.25f, 1e-5f);
  // Collienne 2013, eq. 4.28 with the default key 1 / (2^2.2 - 1) = 0.27818:
  // l_avg = 1000 cd/m² -> EV = log2(1000 / (1.2 * 0.27818)) = 11.548659.
  EXPECT_NEAR(post::DEFAULT_EXPOSURE_KEY, 1.0 / (std::pow(2.0, 2.2) - 1.0), 1e-5);
  EXPECT_NEAR(post::exposure_target_ev(1000.0f, post::DEFAULT_EXPOSURE_KEY, 0.0f, -10.0f, 30.0f), 11.548659f, 1e-4f);
  // Compensation +1 EV (brighter image) lowers the EV by 1; the clamp holds.
  EXPECT_NEAR(post::exposure_target_ev(1000.0f, post::DEFAULT_EXPOSURE_KEY, 1.0f, -10.0f, 30.0f), 10.548659f, 1e-4f);
  EXPECT_EQ(post::exposure_target_ev(1000.0f, post::DEFAULT_EXPOSURE_KEY, 0.0f, -10.0f, 9.0f), 9.0f);
  EXPECT_EQ(post::exposure_target_ev(1000.0f, post::DEFAULT_EXPOSURE_KEY, 0.0f, 12.0f, 14.0f), 12.0f);
  // Adaptation: from EV 10 towards 12 (brighter scene), dt 0.1 s, tau 0.5 s:
  // 12 - 2 e^-0.2 = 10.362538; towards 8 (darker) with tau 2 s: 8 + 2 e^-0.05 = 9.902459.
  EXPECT_NEAR(post::adapted_ev(10.0f, 12.0f, 0.1f, 0.5f, 2.0f), 10.362538f, 1e-5f);
  EXPECT_NEAR(post::adapted_ev(10.0f, 8.0f, 0.1f, 0.5f, 2.0f), 8.0f + 2.0f * std::exp(-0.05f), 1e-5f);
  EXPECT_EQ(post::adapted_ev(10.0f, 8.0f, 0.1f, 0.5f, 0.0f), 8.0f);  // tau 0: instantaneous
}

// Turkowski's incremental weights equal the Gaussian evaluated directly.
TEST(PostBloom, IncrementalGaussianEqualsTheGaussian) {
  for (float sigma : {0.8f, 2.0f, 5.0f}) {
    glm::vec3 g = post::incremental_gaussian_start(sigma);
    for (int k = 0; k <= 15; ++k) {
      const double direct = std::exp(-double(k * k) / (2.0 * sigma * sigma)) / (std::sqrt(2.0 * M_PI) * sigma);
      EXPECT_NEAR(g.x, direct, 1e-5 * direct + 1e-12) << "sigma " << sigma << " k " << k;
      g = post::incremental_gaussian_next(g);
    }
  }
}

TEST(PostSettingsNames, ParseAndName) {
  for (ToneMapping op : kToneMappings) EXPECT_EQ(atmos::parse_tone_mapping(atmos::tone_mapping_name(op)), op);
  EXPECT_THROW(atmos::parse_tone_mapping("hable"), atmos::Error);
}

}  // namespace
