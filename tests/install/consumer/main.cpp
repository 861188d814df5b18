// Uses every layer of an installed atmos through its public headers: a planet
// file from the installed data, small tables, the CPU sky model, a headless
// GPU render and the post-processing's PNG output. Exits non-zero on any
// failure.
#include <atmos/planet_file.hpp>
#include <atmos/colour.hpp>
#include <atmos/post.hpp>
#include <atmos/renderer.hpp>
#include <atmos/sky.hpp>
#include <atmos/tables.hpp>

#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>

int main() {
  try {
    const atmos::Atmosphere mars = atmos::load_atmosphere(std::filesystem::path(ATMOS_DATA_DIR) / "planets" / "mars.json");
    atmos::PrecomputeOptions options;
    options.sizes = {64, 16, 32, 8, 4, 16, 32, 8};
    options.scattering_orders = 2;
    const atmos::Tables tables = atmos::precompute_tables(mars, options);

    const atmos::SkyModel sky(mars, tables);
    const glm::dvec3 zenith = sky.to_srgb(sky.radiance(atmos::observer_position(mars, 2.0),
                                                       glm::dvec3(0.0, 0.0, 1.0),
                                                       atmos::direction_from_azimuth_elevation(0.0, 40.0), false));
    if (!(atmos::srgb_luminance(zenith) > 0.0)) {
      std::fprintf(stderr, "zenith luminance is not positive\n");
      return 1;
    }

    auto context = atmos::GlContext::create_headless();
    atmos::Renderer renderer(mars, tables);
    atmos::Camera camera;
    camera.position = atmos::observer_position(mars, 2.0);
    camera.width = 32;
    camera.height = 16;
    const atmos::Image image = renderer.render(camera, atmos::direction_from_azimuth_elevation(0.0, 40.0));
    for (float v : image.rgb)
      if (!std::isfinite(v) || v < 0.0f) {
        std::fprintf(stderr, "the render holds a negative or non-finite value\n");
        return 1;
      }
    const std::filesystem::path png = std::filesystem::temp_directory_path() / "atmos_consumer.png";
    atmos::write_png(image, png.string(), 10.0);
    std::printf("atmos consumer: Mars zenith %.4g cd/m2, %dx%d render, %s\n", atmos::srgb_luminance(zenith),
                image.width, image.height, png.c_str());
    std::filesystem::remove(png);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "atmos consumer: %s\n", e.what());
    return 1;
  }
}
