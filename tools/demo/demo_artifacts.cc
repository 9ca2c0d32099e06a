#include "tools/demo/demo_artifacts.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <map>
#include <stdexcept>

#include "tools/demo/demo_metrics.h"

namespace rslam::demo {
namespace {

uint8_t MapServerShade(int8_t v) {
  if (v < 0) return 205;
  if (v <= kFreeAtMost) return 254;
  if (v >= kOccupiedAtLeast) return 0;
  return 205;
}

}  // namespace

void WriteMapServerGrid(const msg::OccupancyGrid& grid, const std::filesystem::path& base) {
  if (grid.cells.size() != static_cast<size_t>(grid.width) * grid.height)
    throw std::runtime_error("occupancy grid: cells do not match width x height");
  const std::filesystem::path pgm = base.string() + ".pgm", yaml = base.string() + ".yaml";
  std::ofstream image(pgm, std::ios::binary);
  image << "P5\n" << grid.width << " " << grid.height << "\n255\n";
  std::vector<char> row(grid.width);
  for (int64_t gy = static_cast<int64_t>(grid.height) - 1; gy >= 0; --gy) {
    for (uint32_t gx = 0; gx < grid.width; ++gx)
      row[gx] = static_cast<char>(MapServerShade(grid.cells[static_cast<size_t>(gy) * grid.width + gx]));
    image.write(row.data(), static_cast<std::streamsize>(row.size()));
  }
  std::ofstream meta(yaml);
  meta << "image: " << pgm.filename().string() << "\nresolution: " << grid.resolution_m << "\norigin: ["
       << grid.origin_x_m << ", " << grid.origin_y_m << ", 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
  if (!image || !meta) throw std::runtime_error("cannot write " + pgm.string() + " / " + yaml.string());
}

void WriteExperiencesCsv(const msg::ExperienceMap& map, const DemoObservations& seen,
                         const eval::TrajectoryError* alignment, const std::filesystem::path& path) {
  const std::map<uint32_t, Pose2D> truth_of = ExperienceGroundTruth(seen);
  std::ofstream csv(path);
  // The first four columns as `rslam run`'s experiences.csv.
  csv << "id,x,y,theta,frame_seq,truth_x,truth_y,truth_theta,aligned_x,aligned_y,error_m\n";
  csv << std::setprecision(9);
  for (const auto& e : map.experiences) {
    csv << e.id << "," << e.x_m << "," << e.y_m << "," << e.theta_rad << ",";
    if (const auto first = seen.experience_first_frame.find(e.id); first != seen.experience_first_frame.end())
      csv << first->second;
    const auto truth_it = truth_of.find(e.id);
    const Pose2D* truth = truth_it != truth_of.end() ? &truth_it->second : nullptr;
    if (truth) csv << "," << truth->x << "," << truth->y << "," << truth->theta;
    else csv << ",,,";
    if (alignment) {
      const Eigen::Vector2d p = alignment->Align(e.x_m, e.y_m);
      csv << "," << p.x() << "," << p.y() << ",";
      if (truth) csv << std::hypot(p.x() - truth->x, p.y() - truth->y);
    } else {
      csv << ",,,";
    }
    csv << "\n";
  }
  if (!csv) throw std::runtime_error("cannot write " + path.string());
}

cv::Mat RenderExperienceMap(const sim::WorldMap& world, std::span<const FramePose> truth,
                            const msg::ExperienceMap* map, const eval::TrajectoryError* alignment) {
  // Extent: the true path and the aligned experiences, with a margin.
  double min_x = 1e18, min_y = 1e18, max_x = -1e18, max_y = -1e18;
  auto extend = [&](double x, double y) {
    min_x = std::min(min_x, x), max_x = std::max(max_x, x), min_y = std::min(min_y, y), max_y = std::max(max_y, y);
  };
  for (const auto& p : truth) extend(p.x, p.y);
  std::vector<cv::Point2d> experiences;
  std::map<uint32_t, size_t> index;
  if (map != nullptr && alignment != nullptr) {
    for (const auto& e : map->experiences) {
      const Eigen::Vector2d p = alignment->Align(e.x_m, e.y_m);
      const cv::Point2d w(p.x(), p.y());
      index[e.id] = experiences.size();
      experiences.push_back(w);
      extend(w.x, w.y);
    }
  }
  if (min_x > max_x) {  // nothing to draw: the whole world
    min_x = world.origin().x(), min_y = world.origin().y();
    max_x = min_x + world.width() * world.resolution(), max_y = min_y + world.height() * world.resolution();
  }
  const double margin = 1.0;
  min_x -= margin, min_y -= margin, max_x += margin, max_y += margin;
  const double scale = 900.0 / std::max(max_x - min_x, max_y - min_y);  // pixels per metre
  const int w = std::max(1, static_cast<int>((max_x - min_x) * scale)), h = std::max(1, static_cast<int>((max_y - min_y) * scale));
  cv::Mat image(h, w, CV_8UC3, cv::Scalar(255, 255, 255));
  auto px = [&](double x, double y) { return cv::Point(static_cast<int>((x - min_x) * scale), static_cast<int>((max_y - y) * scale)); };
  // Walls of the world, light grey.
  for (int r = 0; r < h; ++r)
    for (int col = 0; col < w; ++col) {
      const double x = min_x + (col + 0.5) / scale, y = max_y - (r + 0.5) / scale;
      if (world.IsWall(world.WorldToCell({x, y}))) image.at<cv::Vec3b>(r, col) = cv::Vec3b(215, 215, 215);
    }
  for (size_t i = 1; i < truth.size(); ++i)
    cv::line(image, px(truth[i - 1].x, truth[i - 1].y), px(truth[i].x, truth[i].y), cv::Scalar(90, 90, 90), 1, cv::LINE_AA);
  if (map != nullptr && alignment != nullptr) {
    for (const auto& link : map->links) {
      const auto a = index.find(link.from_id), b = index.find(link.to_id);
      if (a == index.end() || b == index.end()) continue;
      const cv::Scalar colour = link.closes_loop ? cv::Scalar(40, 40, 220) : cv::Scalar(60, 170, 60);
      cv::line(image, px(experiences[a->second].x, experiences[a->second].y),
               px(experiences[b->second].x, experiences[b->second].y), colour, link.closes_loop ? 2 : 1, cv::LINE_AA);
    }
    for (const auto& e : experiences) cv::circle(image, px(e.x, e.y), 3, cv::Scalar(200, 90, 30), cv::FILLED, cv::LINE_AA);
  }
  cv::putText(image, "grey: true path   blue: experiences (aligned)   green: links   red: loop closures", {10, 20},
              cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  return image;
}

cv::Mat RenderOccupancy(const msg::OccupancyGrid& grid, std::span<const FramePose> map_path) {
  if (grid.width == 0 || grid.height == 0 || grid.cells.size() != static_cast<size_t>(grid.width) * grid.height)
    return cv::Mat(1, 1, CV_8UC3, cv::Scalar(205, 205, 205));
  int min_x = static_cast<int>(grid.width), min_y = static_cast<int>(grid.height), max_x = -1, max_y = -1;
  for (uint32_t gy = 0; gy < grid.height; ++gy)
    for (uint32_t gx = 0; gx < grid.width; ++gx)
      if (grid.cells[static_cast<size_t>(gy) * grid.width + gx] >= 0) {
        min_x = std::min<int>(min_x, gx), max_x = std::max<int>(max_x, gx);
        min_y = std::min<int>(min_y, gy), max_y = std::max<int>(max_y, gy);
      }
  if (max_x < 0) min_x = min_y = 0, max_x = static_cast<int>(grid.width) - 1, max_y = static_cast<int>(grid.height) - 1;
  const int pad = 10;
  min_x = std::max(0, min_x - pad), min_y = std::max(0, min_y - pad);
  max_x = std::min<int>(grid.width - 1, max_x + pad), max_y = std::min<int>(grid.height - 1, max_y + pad);
  const int w = max_x - min_x + 1, h = max_y - min_y + 1;
  cv::Mat image(h, w, CV_8UC3);
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) {
      const uint8_t shade = MapServerShade(grid.cells[static_cast<size_t>(max_y - r) * grid.width + (min_x + c)]);
      image.at<cv::Vec3b>(r, c) = cv::Vec3b(shade, shade, shade);
    }
  const int zoom = std::max(1, 900 / std::max(w, h));
  cv::resize(image, image, {w * zoom, h * zoom}, 0, 0, cv::INTER_NEAREST);
  auto px = [&](double x, double y) {
    return cv::Point(static_cast<int>(((x - grid.origin_x_m) / grid.resolution_m - min_x) * zoom),
                     static_cast<int>((max_y + 1 - (y - grid.origin_y_m) / grid.resolution_m) * zoom));
  };
  for (size_t i = 1; i < map_path.size(); ++i)
    cv::line(image, px(map_path[i - 1].x, map_path[i - 1].y), px(map_path[i].x, map_path[i].y), cv::Scalar(0, 0, 220), 1,
             cv::LINE_AA);
  return image;
}

cv::Mat RenderGridComparison(const sim::WorldMap& world, std::span<const Eigen::Vector2i> reachable,
                             const Pose2D& map_origin, const msg::OccupancyGrid& grid, double tolerance_m) {
  const int margin = static_cast<int>(std::ceil(1.0 / world.resolution()));
  int min_x = world.width() - 1, min_y = world.height() - 1, max_x = 0, max_y = 0;
  for (const auto& c : reachable)
    min_x = std::min(min_x, c.x()), max_x = std::max(max_x, c.x()), min_y = std::min(min_y, c.y()), max_y = std::max(max_y, c.y());
  if (reachable.empty()) min_x = min_y = 0, max_x = world.width() - 1, max_y = world.height() - 1;
  min_x -= margin, min_y -= margin, max_x += margin, max_y += margin;
  const int w = max_x - min_x + 1, h = max_y - min_y + 1;
  std::vector<bool> is_reachable(static_cast<size_t>(w) * h, false);
  for (const auto& c : reachable) is_reachable[static_cast<size_t>(c.y() - min_y) * w + (c.x() - min_x)] = true;
  cv::Mat image(h, w, CV_8UC3);
  for (int iy = min_y; iy <= max_y; ++iy)
    for (int ix = min_x; ix <= max_x; ++ix) {
      const Eigen::Vector2i cell(ix, iy);
      const Eigen::Vector2d p = world.CellCenter(cell);
      const int v = GridValueAtWorldPoint(grid, map_origin, p);
      const bool free = v >= 0 && v <= kFreeAtMost, occupied = v >= kOccupiedAtLeast;
      cv::Vec3b colour;  // BGR
      if (is_reachable[static_cast<size_t>(iy - min_y) * w + (ix - min_x)])
        colour = free ? cv::Vec3b(255, 255, 255) : v < 0 ? cv::Vec3b(0, 150, 255)
                 : occupied                            ? cv::Vec3b(40, 40, 220)
                                                       : cv::Vec3b(0, 215, 255);
      else if (world.IsWall(cell))
        colour = free && !WorldHasNear(world, p, true, tolerance_m) ? cv::Vec3b(220, 120, 0)
                 : occupied                                           ? cv::Vec3b(0, 0, 0)
                                                                      : cv::Vec3b(150, 150, 150);
      else
        colour = occupied && !WorldHasNear(world, p, false, tolerance_m) ? cv::Vec3b(200, 0, 200) : cv::Vec3b(225, 225, 225);
      image.at<cv::Vec3b>(max_y - iy, ix - min_x) = colour;  // first row = top (largest y)
    }
  const int zoom = std::max(1, 1000 / std::max(w, h));
  cv::resize(image, image, {w * zoom, h * zoom}, 0, 0, cv::INTER_NEAREST);
  cv::copyMakeBorder(image, image, 40, 0, 0, 0, cv::BORDER_CONSTANT, cv::Scalar(255, 255, 255));
  cv::putText(image, "reachable cells: white free, orange unknown, yellow uncertain, red occupied", {6, 16},
              cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  cv::putText(image, "blue: free on a wall   magenta: occupied off walls   grey: walls (black: marked)", {6, 32},
              cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  return image;
}

}  // namespace rslam::demo
