// atmos — the camera model: from a pixel to a view ray.
//
// Shared by the GPU renderer (render.frag.glsl, after the physics) and the
// CPU twin (gpu/camera_cpp.hpp), so that both trace exactly the same rays.
// Written in the GLSL / C++ subset described at the top of
// physics/definitions.glsl (f-suffixed literals, IN/OUT/INLINE, no swizzles).

#define PROJECTION_PERSPECTIVE 0
#define PROJECTION_FISHEYE 1
#define PROJECTION_EQUIRECT 2

// The unit view ray through `pixel`, the pixel centre in image coordinates:
// x to the right and y downwards from the top-left corner, so (0.5, 0.5) is the
// centre of the top-left pixel and `image_size` the bottom-right corner.
// `right`, `up`, `forward` are the orthonormal camera basis (planet frame);
// `fov_deg` is the vertical field of view (perspective) or the full field of
// the fisheye circle. `lens_shift` (perspective only) moves the image plane
// in its own plane, in units of the forward distance: the image centre looks
// along forward + right lens_shift.x + up lens_shift.y, an off-axis frustum
// (a stereo eye's: atmos/stereo.hpp). `valid` is false for fisheye pixels
// outside the circle.
INLINE vec3 camera_view_ray(vec2 pixel, vec2 image_size, vec3 right, vec3 up, vec3 forward, float fov_deg,
                            vec2 lens_shift, int projection, OUT(bool) valid) {
  valid = true;
  if (projection == PROJECTION_EQUIRECT) {
    // Azimuth -180..180° left to right (0 = forward, +90° = right), elevation
    // +90° (top edge) .. -90° (bottom edge).
    float azimuth = (pixel.x / image_size.x - 0.5f) * (2.0f * PI);
    float elevation = (0.5f - pixel.y / image_size.y) * PI;
    float horizontal = cos(elevation);
    return normalize(forward * (horizontal * cos(azimuth)) + right * (horizontal * sin(azimuth)) +
                     up * sin(elevation));
  }
  // Offset from the image centre in pixels, y upwards.
  float x = pixel.x - 0.5f * image_size.x;
  float y = 0.5f * image_size.y - pixel.y;
  if (projection == PROJECTION_FISHEYE) {
    // Equidistant: the angle from the axis is proportional to the distance
    // from the centre, fov / 2 on the largest circle centred in the image.
    float radius = 0.5f * min(image_size.x, image_size.y);
    float rho = sqrt(x * x + y * y);
    if (rho > radius) {
      valid = false;
      return forward;
    }
    float theta = rho / radius * radians(fov_deg) * 0.5f;
    // sin(theta) times the unit vector (x, y) / rho of the image plane.
    float s = rho > 0.0f ? sin(theta) / rho : 0.0f;
    return normalize(forward * cos(theta) + right * (x * s) + up * (y * s));
  }
  // Perspective (pinhole): the image plane at distance 1 spans
  // tan(fov / 2) from its centre to the top edge; square pixels.
  float scale = tan(radians(fov_deg) * 0.5f) / (0.5f * image_size.y);
  return normalize(forward + right * (x * scale + lens_shift.x) + up * (y * scale + lens_shift.y));
}
