#include "tools/sim/world_map.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <filesystem>
#include <fstream>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>

namespace rslam::sim {

namespace {

std::vector<uint8_t> MakePaddedWalls(int width, int height, const std::vector<CellClass>& cells) {
  const int pw = width + 2;
  std::vector<uint8_t> walls(static_cast<size_t>(pw) * (height + 2), 1);
  for (int iy = 0; iy < height; ++iy) {
    for (int ix = 0; ix < width; ++ix) {
      walls[static_cast<size_t>(iy + 1) * pw + ix + 1] =
          cells[static_cast<size_t>(iy) * width + ix] == CellClass::kFree ? 0 : 1;
    }
  }
  return walls;
}

[[noreturn]] void Fail(const std::string& file, const std::string& problem) {
  throw WorldFileError("world file " + file + ": " + problem);
}

struct Pgm {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> pixels;  // row 0 = top, scaled to 0-255
};

Pgm ReadBinaryPgm(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) Fail(path, "cannot open the image");
  std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  size_t pos = 0;
  auto skip_space_and_comments = [&] {
    while (pos < data.size()) {
      if (data[pos] == '#') {
        while (pos < data.size() && data[pos] != '\n') ++pos;
      } else if (std::isspace(static_cast<unsigned char>(data[pos]))) {
        ++pos;
      } else {
        break;
      }
    }
  };
  auto read_int = [&](const char* what) {
    skip_space_and_comments();
    size_t start = pos;
    while (pos < data.size() && std::isdigit(static_cast<unsigned char>(data[pos]))) ++pos;
    if (start == pos || pos - start > 9) Fail(path, std::string("bad PGM header: no valid ") + what);
    return std::stoi(data.substr(start, pos - start));
  };
  if (data.size() < 2 || data[0] != 'P' || data[1] != '5') {
    Fail(path, "not a binary PGM image (expected magic 'P5')");
  }
  pos = 2;
  Pgm pgm;
  pgm.width = read_int("width");
  pgm.height = read_int("height");
  const int maxval = read_int("maxval");
  if (pgm.width <= 0 || pgm.height <= 0 || pgm.width > 100000 || pgm.height > 100000) {
    Fail(path, "bad PGM size " + std::to_string(pgm.width) + "x" + std::to_string(pgm.height));
  }
  if (maxval <= 0 || maxval > 255) Fail(path, "PGM maxval must be 1-255 (8-bit), got " + std::to_string(maxval));
  if (pos >= data.size() || !std::isspace(static_cast<unsigned char>(data[pos]))) {
    Fail(path, "bad PGM header: no whitespace before the pixel data");
  }
  ++pos;
  const size_t expected = static_cast<size_t>(pgm.width) * pgm.height;
  if (data.size() - pos < expected) {
    Fail(path, "truncated PGM: expected " + std::to_string(expected) + " pixel bytes, got " +
                   std::to_string(data.size() - pos));
  }
  pgm.pixels.resize(expected);
  for (size_t i = 0; i < expected; ++i) {
    const int v = static_cast<unsigned char>(data[pos + i]);
    pgm.pixels[i] = static_cast<uint8_t>(std::lround(std::min(v, maxval) * 255.0 / maxval));
  }
  return pgm;
}

double RequireNumber(const YAML::Node& root, const std::string& key, const std::string& file) {
  const YAML::Node n = root[key];
  if (!n) Fail(file, "missing key '" + key + "'");
  if (!n.IsScalar()) Fail(file, "key '" + key + "' must be a number");
  double v = 0;
  try {
    v = n.as<double>();
  } catch (const YAML::Exception&) {
    Fail(file, "key '" + key + "' must be a number, got '" + n.Scalar() + "'");
  }
  if (!std::isfinite(v)) Fail(file, "key '" + key + "' must be finite");
  return v;
}

}  // namespace

WorldMap::WorldMap(int width, int height, double resolution, Eigen::Vector2d origin,
                   std::vector<CellClass> cells)
    : width_(width),
      height_(height),
      resolution_(resolution),
      origin_(origin),
      cells_(std::move(cells)),
      padded_width_(width + 2),
      walls_(width > 0 && height > 0 && cells_.size() == static_cast<size_t>(width) * height
                 ? MakePaddedWalls(width, height, cells_)
                 : std::vector<uint8_t>()) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("WorldMap: width and height must be positive");
  if (cells_.size() != static_cast<size_t>(width) * height) {
    throw std::invalid_argument("WorldMap: cells has " + std::to_string(cells_.size()) + " entries, expected " +
                                std::to_string(static_cast<size_t>(width) * height));
  }
  if (!std::isfinite(resolution) || resolution <= 0) {
    throw std::invalid_argument("WorldMap: resolution must be positive and finite");
  }
  if (!origin.allFinite()) throw std::invalid_argument("WorldMap: origin must be finite");
}

WorldMap WorldMap::LoadFromYaml(const std::string& yaml_path) {
  YAML::Node root;
  try {
    if (!std::filesystem::exists(yaml_path)) Fail(yaml_path, "does not exist");
    root = YAML::LoadFile(yaml_path);
  } catch (const YAML::Exception& e) {
    Fail(yaml_path, std::string("not valid YAML: ") + e.what());
  }
  if (!root.IsMap()) Fail(yaml_path, "expected a YAML map with keys image, resolution, origin, ...");
  static const std::set<std::string> kKnown = {"image",     "resolution",      "origin",     "negate",
                                               "occupied_thresh", "free_thresh", "mode"};
  for (const auto& kv : root) {
    const std::string key = kv.first.as<std::string>();
    if (!kKnown.count(key)) Fail(yaml_path, "unknown key '" + key + "'");
  }
  if (!root["image"] || !root["image"].IsScalar() || root["image"].Scalar().empty()) {
    Fail(yaml_path, "missing key 'image' (the PGM file name)");
  }
  const double resolution = RequireNumber(root, "resolution", yaml_path);
  if (resolution <= 0) Fail(yaml_path, "key 'resolution' must be positive");
  const YAML::Node origin_node = root["origin"];
  if (!origin_node) Fail(yaml_path, "missing key 'origin'");
  if (!origin_node.IsSequence() || origin_node.size() != 3) {
    Fail(yaml_path, "key 'origin' must be a list [x, y, yaw]");
  }
  double origin[3];
  for (int i = 0; i < 3; ++i) {
    try {
      origin[i] = origin_node[i].as<double>();
    } catch (const YAML::Exception&) {
      Fail(yaml_path, "key 'origin' must hold 3 numbers");
    }
    if (!std::isfinite(origin[i])) Fail(yaml_path, "key 'origin' must hold finite numbers");
  }
  if (std::abs(origin[2]) > 1e-9) Fail(yaml_path, "rotated maps (origin yaw != 0) are not supported");
  const double negate = RequireNumber(root, "negate", yaml_path);
  if (negate != 0 && negate != 1) Fail(yaml_path, "key 'negate' must be 0 or 1");
  const double occupied_thresh = RequireNumber(root, "occupied_thresh", yaml_path);
  const double free_thresh = RequireNumber(root, "free_thresh", yaml_path);
  if (occupied_thresh <= 0 || occupied_thresh > 1) Fail(yaml_path, "key 'occupied_thresh' must be in (0, 1]");
  if (free_thresh < 0 || free_thresh >= occupied_thresh) {
    Fail(yaml_path, "key 'free_thresh' must be in [0, occupied_thresh)");
  }
  if (root["mode"] && (!root["mode"].IsScalar() || root["mode"].Scalar() != "trinary")) {
    Fail(yaml_path, "key 'mode' must be 'trinary' (the only supported mode)");
  }

  std::filesystem::path image = root["image"].Scalar();
  if (image.is_relative()) image = std::filesystem::path(yaml_path).parent_path() / image;
  if (!std::filesystem::exists(image)) Fail(yaml_path, "image '" + image.string() + "' does not exist");
  const Pgm pgm = ReadBinaryPgm(image.string());

  std::vector<CellClass> cells(static_cast<size_t>(pgm.width) * pgm.height);
  for (int row = 0; row < pgm.height; ++row) {
    const int iy = pgm.height - 1 - row;  // image row 0 is the top of the map
    for (int ix = 0; ix < pgm.width; ++ix) {
      const double v = pgm.pixels[static_cast<size_t>(row) * pgm.width + ix];
      const double occupancy = negate != 0 ? v / 255.0 : (255.0 - v) / 255.0;  // map_server trinary
      CellClass c = CellClass::kUnknown;
      if (occupancy > occupied_thresh) c = CellClass::kOccupied;
      else if (occupancy < free_thresh) c = CellClass::kFree;
      cells[static_cast<size_t>(iy) * pgm.width + ix] = c;
    }
  }
  return WorldMap(pgm.width, pgm.height, resolution, Eigen::Vector2d(origin[0], origin[1]), std::move(cells));
}

CellClass WorldMap::Classify(const Eigen::Vector2i& cell) const {
  if (!InBounds(cell)) return CellClass::kUnknown;
  return cells_[static_cast<size_t>(cell.y()) * width_ + cell.x()];
}

Eigen::Vector2i WorldMap::WorldToCell(const Eigen::Vector2d& p) const {
  const Eigen::Vector2d g = WorldToGrid(p);
  return Eigen::Vector2i(static_cast<int>(std::floor(g.x())), static_cast<int>(std::floor(g.y())));
}

Eigen::Vector2d WorldMap::CellCenter(const Eigen::Vector2i& cell) const {
  return origin_ + resolution_ * (cell.cast<double>() + Eigen::Vector2d(0.5, 0.5));
}

RayHit WorldMap::CastRay(const Eigen::Vector2d& from, double angle) const {
  if (!std::isfinite(angle)) throw std::invalid_argument("CastRay: angle must be finite");
  return CastRay(from, Eigen::Vector2d(std::cos(angle), std::sin(angle)));
}

RayHit WorldMap::CastRay(const Eigen::Vector2d& from, const Eigen::Vector2d& dir) const {
  if (!from.allFinite() || !dir.allFinite()) throw std::invalid_argument("CastRay: non-finite input");
  const Eigen::Vector2d g = WorldToGrid(from);
  RayHit hit;
  hit.point = from;
  if (!(g.x() >= -1.0 && g.y() >= -1.0 && g.x() < width_ + 1.0 && g.y() < height_ + 1.0)) {
    hit.cell = WorldToCell(from);  // outside the building: inside a wall
    return hit;
  }
  int ix = static_cast<int>(std::floor(g.x()));
  int iy = static_cast<int>(std::floor(g.y()));
  const uint8_t* walls = walls_.data();
  const int pw = padded_width_;
  size_t index = static_cast<size_t>(iy + 1) * pw + (ix + 1);
  if (walls[index]) {
    hit.cell = Eigen::Vector2i(ix, iy);
    return hit;
  }
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const double dx = dir.x(), dy = dir.y();
  const int step_x = dx > 0 ? 1 : -1;
  const int step_y = dy > 0 ? 1 : -1;
  // Grid units and metres differ by the resolution only, so t is measured in cells.
  double t_max_x = dx != 0 ? ((ix + (dx > 0 ? 1 : 0)) - g.x()) / dx : kInf;
  double t_max_y = dy != 0 ? ((iy + (dy > 0 ? 1 : 0)) - g.y()) / dy : kInf;
  const double t_delta_x = dx != 0 ? std::abs(1.0 / dx) : kInf;
  const double t_delta_y = dy != 0 ? std::abs(1.0 / dy) : kInf;
  const ptrdiff_t index_step_y = step_y * static_cast<ptrdiff_t>(pw);
  double t = 0;
  int face = 0;
  for (;;) {
    if (t_max_x < t_max_y) {
      ix += step_x;
      index += step_x;
      t = t_max_x;
      t_max_x += t_delta_x;
      face = dx > 0 ? 0 : 1;
    } else {
      iy += step_y;
      index += index_step_y;
      t = t_max_y;
      t_max_y += t_delta_y;
      face = dy > 0 ? 2 : 3;
    }
    if (walls[index]) break;  // the one-cell wall border guarantees this ends
  }
  hit.distance = t * resolution_;
  hit.point = from + hit.distance * dir;
  hit.cell = Eigen::Vector2i(ix, iy);
  hit.face = face;
  return hit;
}

bool WorldMap::IsDiscFree(const Eigen::Vector2d& p, double radius) const {
  if (!p.allFinite() || !std::isfinite(radius) || radius < 0) {
    throw std::invalid_argument("IsDiscFree: non-finite position or bad radius");
  }
  const Eigen::Vector2d g = WorldToGrid(p);
  const double r = radius / resolution_;
  const int x0 = static_cast<int>(std::floor(g.x() - r)), x1 = static_cast<int>(std::floor(g.x() + r));
  const int y0 = static_cast<int>(std::floor(g.y() - r)), y1 = static_cast<int>(std::floor(g.y() + r));
  for (int iy = y0; iy <= y1; ++iy) {
    for (int ix = x0; ix <= x1; ++ix) {
      if (!IsWall(Eigen::Vector2i(ix, iy))) continue;
      // Distance from the disc centre to the cell square.
      const double cx = std::clamp(g.x(), static_cast<double>(ix), ix + 1.0);
      const double cy = std::clamp(g.y(), static_cast<double>(iy), iy + 1.0);
      const double ddx = g.x() - cx, ddy = g.y() - cy;
      if (ddx * ddx + ddy * ddy < r * r || (ddx == 0 && ddy == 0)) return false;
    }
  }
  return true;
}

std::vector<Eigen::Vector2i> WorldMap::ReachableFreeCells(const Eigen::Vector2d& start, double robot_radius_m) const {
  std::vector<Eigen::Vector2i> out;
  if (!start.allFinite()) throw std::invalid_argument("ReachableFreeCells: non-finite start");
  if (!std::isfinite(robot_radius_m) || robot_radius_m < 0) {
    throw std::invalid_argument("ReachableFreeCells: robot radius must be finite and >= 0");
  }
  const auto enterable = [&](const Eigen::Vector2i& c) {
    return Classify(c) == CellClass::kFree && (robot_radius_m == 0.0 || IsDiscFree(CellCenter(c), robot_radius_m));
  };
  const Eigen::Vector2i s = WorldToCell(start);
  if (!enterable(s)) return out;
  std::vector<uint8_t> seen(cells_.size(), 0);
  std::deque<Eigen::Vector2i> queue{s};
  seen[static_cast<size_t>(s.y()) * width_ + s.x()] = 1;
  static const int kDx[4] = {1, -1, 0, 0}, kDy[4] = {0, 0, 1, -1};
  while (!queue.empty()) {
    const Eigen::Vector2i c = queue.front();
    queue.pop_front();
    out.push_back(c);
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector2i n(c.x() + kDx[k], c.y() + kDy[k]);
      if (Classify(n) != CellClass::kFree) continue;
      uint8_t& flag = seen[static_cast<size_t>(n.y()) * width_ + n.x()];
      if (flag) continue;
      flag = 1;
      if (!enterable(n)) continue;
      queue.push_back(n);
    }
  }
  std::sort(out.begin(), out.end(), [](const Eigen::Vector2i& a, const Eigen::Vector2i& b) {
    return a.y() != b.y() ? a.y() < b.y() : a.x() < b.x();
  });
  return out;
}

std::vector<float> WorldMap::DistanceToWalls() const {
  // Pad with walls so the outside of the map counts as wall.
  cv::Mat free_mask(height_ + 2, width_ + 2, CV_8UC1, cv::Scalar(0));
  for (int iy = 0; iy < height_; ++iy) {
    for (int ix = 0; ix < width_; ++ix) {
      free_mask.at<uint8_t>(iy + 1, ix + 1) =
          cells_[static_cast<size_t>(iy) * width_ + ix] == CellClass::kFree ? 255 : 0;
    }
  }
  cv::Mat dist;
  cv::distanceTransform(free_mask, dist, cv::DIST_L2, cv::DIST_MASK_PRECISE, CV_32F);
  std::vector<float> out(cells_.size());
  for (int iy = 0; iy < height_; ++iy) {
    for (int ix = 0; ix < width_; ++ix) {
      out[static_cast<size_t>(iy) * width_ + ix] = dist.at<float>(iy + 1, ix + 1) * static_cast<float>(resolution_);
    }
  }
  return out;
}

Pose2D WorldMap::DefaultStartPose() const {
  cv::Mat free_mask(height_, width_, CV_8UC1);
  for (int iy = 0; iy < height_; ++iy) {
    for (int ix = 0; ix < width_; ++ix) {
      free_mask.at<uint8_t>(iy, ix) = cells_[static_cast<size_t>(iy) * width_ + ix] == CellClass::kFree ? 1 : 0;
    }
  }
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(free_mask, labels, stats, centroids, 4, CV_32S);
  if (n <= 1) throw std::invalid_argument("DefaultStartPose: the world has no free cell");
  int best_label = 1;
  for (int l = 2; l < n; ++l) {
    if (stats.at<int>(l, cv::CC_STAT_AREA) > stats.at<int>(best_label, cv::CC_STAT_AREA)) best_label = l;
  }
  // Farthest from walls; among equally far cells (a corridor's centre line) the one nearest the
  // region's centroid, then the lowest (iy, ix), so the choice is deterministic and central.
  const std::vector<float> dist = DistanceToWalls();
  const double cx = centroids.at<double>(best_label, 0), cy = centroids.at<double>(best_label, 1);
  float best = -1;
  double best_to_centroid = 0;
  Eigen::Vector2i best_cell(0, 0);
  for (int iy = 0; iy < height_; ++iy) {
    for (int ix = 0; ix < width_; ++ix) {
      if (labels.at<int>(iy, ix) != best_label) continue;
      const float d = dist[static_cast<size_t>(iy) * width_ + ix];
      const double to_centroid = std::hypot(ix - cx, iy - cy);
      if (d > best + 1e-4f || (d > best - 1e-4f && to_centroid < best_to_centroid - 1e-9)) {
        best = std::max(best, d);
        best_to_centroid = to_centroid;
        best_cell = Eigen::Vector2i(ix, iy);
      }
    }
  }
  const Eigen::Vector2d c = CellCenter(best_cell);
  return Pose2D{c.x(), c.y(), 0.0};
}

}  // namespace rslam::sim
