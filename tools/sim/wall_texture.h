#pragma once
// Deterministic, varied wall textures. A wall face is cut into panels of texture_panel_m along
// the wall; each panel's pattern (bands, stripes, checker, poster, blob, diagonal stripes,
// gradient, wainscot) and colours are a hash of the panel's world position and the face's
// orientation, so different places look different and a place looks the same on a return.
// Panel edges carry a dark seam (a vertical edge for visual odometry) and every texel a fine
// grain, so close-up walls are not flat.
// Every texel channel differs from the floor colour's by at least 20 levels, so with pixel noise
// up to 16 levels floor segmentation by colour stays exact.

#include <opencv2/core.hpp>

#include <cstdint>
#include <vector>

#include "tools/sim/sim_config.h"
#include "tools/sim/world_map.h"

namespace rslam::sim {

class WallTexture {
 public:
  static constexpr int kPatterns = 256;      // distinct panel textures in the atlas
  static constexpr int kTexelsAcross = 32;   // texels across one panel
  static constexpr int kTexelsUp = 64;       // texels from the floor to the top of the wall

  explicit WallTexture(const SceneConfig& scene);
  WallTexture(const WallTexture&) = delete;
  WallTexture& operator=(const WallTexture&) = delete;

  // The texel column (kTexelsUp BGR texels, index 0 at the floor) seen at a wall hit.
  const uint8_t* Column(const RayHit& hit) const;
  // The colour at a wall hit and height z above the floor (clamped to the wall).
  cv::Vec3b Sample(const RayHit& hit, double z) const;

  double texels_per_metre_up() const { return texels_per_metre_up_; }

 private:
  const double panel_m_;
  const uint32_t seed_;
  const double texels_per_metre_up_;
  // Column-major atlas: [pattern][u][v][bgr].
  const std::vector<uint8_t> atlas_;
};

}  // namespace rslam::sim
