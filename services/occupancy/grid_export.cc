#include "services/occupancy/grid_export.h"

#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>

namespace rslam::occupancy {

cv::Mat RenderMapImage(const OccupancyGrid& grid, const MapExportThresholds& thresholds) {
  cv::Mat image(grid.height(), grid.width(), CV_8U);
  for (int y = 0; y < grid.height(); ++y) {
    uchar* row = image.ptr<uchar>(grid.height() - 1 - y);
    for (int x = 0; x < grid.width(); ++x) {
      const CellIndex c{x, y};
      if (!grid.IsKnown(c)) { row[x] = 205; continue; }
      const double p = grid.Probability(c);
      row[x] = p > thresholds.occupied_above ? 0 : (p < thresholds.free_below ? 254 : 205);
    }
  }
  return image;
}

void WriteRosMap(const OccupancyGrid& grid, const std::filesystem::path& base,
                 const MapExportThresholds& thresholds) {
  const cv::Mat image = RenderMapImage(grid, thresholds);
  std::filesystem::path pgm = base, yaml = base;
  pgm += ".pgm";
  yaml += ".yaml";
  {
    std::ofstream out(pgm, std::ios::binary);
    out << "P5\n" << image.cols << " " << image.rows << "\n255\n";
    for (int r = 0; r < image.rows; ++r) out.write(reinterpret_cast<const char*>(image.ptr(r)), image.cols);
    if (!out) throw std::runtime_error("cannot write " + pgm.string());
  }
  std::ofstream out(yaml);
  const GridConfig& g = grid.grid_config();
  out << "image: " << pgm.filename().string() << "\n"
      << "resolution: " << g.resolution_m << "\n"
      << "origin: [" << g.origin_x_m << ", " << g.origin_y_m << ", 0.0]\n"
      << "negate: 0\n"
      << "occupied_thresh: " << thresholds.occupied_above << "\n"
      << "free_thresh: " << thresholds.free_below << "\n";
  if (!out) throw std::runtime_error("cannot write " + yaml.string());
}

void WritePng(const OccupancyGrid& grid, const std::filesystem::path& png_path,
              const MapExportThresholds& thresholds) {
  if (!cv::imwrite(png_path.string(), RenderMapImage(grid, thresholds)))
    throw std::runtime_error("cannot write " + png_path.string());
}

}  // namespace rslam::occupancy
