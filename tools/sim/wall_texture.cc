#include "tools/sim/wall_texture.h"

#include "tools/sim/deterministic_random.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>

namespace rslam::sim {

namespace {

using HashStream = DeterministicRandom;

using Bgr = std::array<int, 3>;

int L1(const Bgr& a, const std::vector<int>& b) {
  return std::abs(a[0] - b[0]) + std::abs(a[1] - b[1]) + std::abs(a[2] - b[2]);
}

// A colour far from the floor (segmentation must never mistake a wall for floor) and not equal
// to the ceiling.
Bgr PickColour(HashStream& h, const SceneConfig& scene) {
  for (;;) {
    Bgr c{h.Int(10, 245), h.Int(10, 245), h.Int(10, 245)};
    if (L1(c, scene.floor_bgr) >= 90 && L1(c, scene.ceiling_bgr) >= 30) return c;  // > 3 x grain
  }
}

// Every channel at least kFloorMargin from the floor's: pixel noise (at most 16 levels) can then
// never turn a wall pixel into the floor colour.
constexpr int kFloorMargin = 20;
void KeepAwayFromFloor(const std::vector<int>& floor, Bgr& colour) {
  for (int k = 0; k < 3; ++k) {
    colour[k] = std::clamp(colour[k], 0, 255);
    if (std::abs(colour[k] - floor[k]) >= kFloorMargin) continue;
    const bool up = colour[k] >= floor[k] ? floor[k] + kFloorMargin <= 255 : floor[k] - kFloorMargin < 0;
    colour[k] = up ? floor[k] + kFloorMargin : floor[k] - kFloorMargin;
  }
}

Bgr Mix(const Bgr& a, const Bgr& b, double w) {
  return {static_cast<int>(std::lround(a[0] + (b[0] - a[0]) * w)),
          static_cast<int>(std::lround(a[1] + (b[1] - a[1]) * w)),
          static_cast<int>(std::lround(a[2] + (b[2] - a[2]) * w))};
}

std::vector<uint8_t> BuildAtlas(const SceneConfig& scene) {
  constexpr int kU = WallTexture::kTexelsAcross, kV = WallTexture::kTexelsUp;
  std::vector<uint8_t> atlas(static_cast<size_t>(WallTexture::kPatterns) * kU * kV * 3);
  // Physical aspect so blobs are round: u spans the panel width, v the wall height.
  const double aspect = scene.wall_height_m / scene.texture_panel_m;
  for (int p = 0; p < WallTexture::kPatterns; ++p) {
    HashStream h(SplitMix64(scene.texture_seed * 0x100000001B3ull + p));
    const Bgr a = PickColour(h, scene), b = PickColour(h, scene), c = PickColour(h, scene);
    const int kind = p % 8;  // every pattern kind appears equally often
    const int n1 = h.Int(2, 7), n2 = h.Int(2, 5);
    const double u0 = h.Uniform() * 0.5, u1 = u0 + 0.25 + h.Uniform() * 0.25;
    const double v0 = 0.2 + h.Uniform() * 0.4, v1 = v0 + 0.15 + h.Uniform() * 0.3;
    const double radius = 0.15 + 0.25 * h.Uniform();
    const double phase = h.Uniform();
    for (int iu = 0; iu < kU; ++iu) {
      for (int iv = 0; iv < kV; ++iv) {
        const double u = (iu + 0.5) / kU, v = (iv + 0.5) / kV;
        Bgr colour = a;
        switch (kind) {
          case 0:  // horizontal bands
            colour = static_cast<int>(v * n1 * 2) % 2 ? a : b;
            break;
          case 1:  // vertical stripes
            colour = static_cast<int>(u * n1 * 2) % 2 ? a : b;
            break;
          case 2:  // checker
            colour = (static_cast<int>(u * n2) + static_cast<int>(v * n1)) % 2 ? a : b;
            break;
          case 3:  // poster: a framed rectangle on a plain wall
            if (u > u0 && u < u1 && v > v0 && v < std::min(v1, 0.95)) {
              const bool frame = u < u0 + 0.04 || u > u1 - 0.04 || v < v0 + 0.03 || v > std::min(v1, 0.95) - 0.03;
              colour = frame ? c : b;
            }
            break;
          case 4: {  // blob
            const double du = (u - (0.3 + 0.4 * phase)) / aspect, dv = v - (v0 + 0.15);
            if (du * du + dv * dv < radius * radius * 0.5) colour = b;
            break;
          }
          case 5:  // diagonal stripes
            colour = static_cast<int>(std::floor((u / aspect + v + phase) * n1 * 2)) % 2 ? a : b;
            break;
          case 6:  // vertical gradient with a stripe
            colour = std::abs(v - v0) < 0.04 ? c : Mix(a, b, v);
            break;
          default:  // wainscot: lower part, rail, upper part
            colour = v < v0 ? a : (v < v0 + 0.05 ? c : b);
            break;
        }
        if (iu == 0) colour = Mix(colour, Bgr{20, 20, 20}, 0.7);  // seam at the panel edge
        // Fine grain so a wall seen from close up still has texture for visual odometry.
        const int grain = static_cast<int>(SplitMix64(p * 1000003ull + iu * 1009ull + iv) % 25) - 12;
        for (int& channel : colour) channel += grain;
        KeepAwayFromFloor(scene.floor_bgr, colour);
        uint8_t* texel = &atlas[((static_cast<size_t>(p) * kU + iu) * kV + iv) * 3];
        for (int k = 0; k < 3; ++k) texel[k] = static_cast<uint8_t>(std::clamp(colour[k], 0, 255));
      }
    }
  }
  return atlas;
}

}  // namespace

WallTexture::WallTexture(const SceneConfig& scene)
    : panel_m_((scene.Validate(), scene.texture_panel_m)),
      seed_(scene.texture_seed),
      texels_per_metre_up_(kTexelsUp / scene.wall_height_m),
      atlas_(BuildAtlas(scene)) {}

const uint8_t* WallTexture::Column(const RayHit& hit) const {
  // Along-wall coordinate s and the face line's coordinate across the wall.
  const bool x_face = hit.face <= 1;
  const double along = x_face ? hit.point.y() : hit.point.x();
  const double across = x_face ? hit.point.x() : hit.point.y();
  // Mirror so each face's texture reads left-to-right as seen from the free side.
  const bool mirrored = hit.face == 0 || hit.face == 3;
  const double s = (mirrored ? -along : along) / panel_m_;
  const double panel = std::floor(s);
  // The cross-wall bucket is 4 panels wide: laser-map walls are jagged by a cell or two.
  const int64_t key_across = static_cast<int64_t>(std::floor(across / (4.0 * panel_m_)));
  uint64_t key = SplitMix64(seed_ ^ 0xC0FFEEull);
  key = SplitMix64(key ^ static_cast<uint64_t>(hit.face));
  key = SplitMix64(key ^ static_cast<uint64_t>(key_across));
  key = SplitMix64(key ^ static_cast<uint64_t>(static_cast<int64_t>(panel)));
  const int pattern = static_cast<int>(key % kPatterns);
  const int iu = std::clamp(static_cast<int>((s - panel) * kTexelsAcross), 0, kTexelsAcross - 1);
  return &atlas_[((static_cast<size_t>(pattern) * kTexelsAcross + iu) * kTexelsUp) * 3];
}

cv::Vec3b WallTexture::Sample(const RayHit& hit, double z) const {
  const uint8_t* column = Column(hit);
  const int iv = std::clamp(static_cast<int>(z * texels_per_metre_up_), 0, kTexelsUp - 1);
  return cv::Vec3b(column[iv * 3], column[iv * 3 + 1], column[iv * 3 + 2]);
}

}  // namespace rslam::sim
