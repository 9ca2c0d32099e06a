#include "tools/run/plot_axes.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace rslam::run {

namespace {

constexpr int kLeft = 80, kRight = 30, kTop = 50, kBottom = 60;
const cv::Scalar kInk(40, 40, 40);
const cv::Scalar kGrid(225, 225, 225);
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;

PlotRange Widen(PlotRange r) {
  if (!(r.max > r.min)) {
    const double pad = std::max(1.0, std::abs(r.min) * 0.1);
    r.min -= pad;
    r.max += pad;
  }
  return r;
}

std::string TickLabel(double value, double step) {
  char buffer[32];
  if (std::abs(value) < step * 1e-6) value = 0.0;
  const int decimals = step >= 1.0 ? 0 : static_cast<int>(std::ceil(-std::log10(step) - 1e-9));
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  return buffer;
}

void PutCentred(cv::Mat& image, const std::string& text, cv::Point centre, double scale) {
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, kFont, scale, 1, &baseline);
  cv::putText(image, text, {centre.x - size.width / 2, centre.y + size.height / 2}, kFont, scale, kInk, 1, cv::LINE_AA);
}

}  // namespace

double NiceTickStep(double span, int target) {
  if (!(span > 0) || target < 1) return 1.0;
  const double raw = span / target;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const double fraction = raw / magnitude;
  const double nice = fraction <= 1.0 ? 1.0 : fraction <= 2.0 ? 2.0 : fraction <= 5.0 ? 5.0 : 10.0;
  return nice * magnitude;
}

PlotAxes::PlotAxes(cv::Size canvas, PlotRange x, PlotRange y, bool equal_scale)
    : canvas_(canvas),
      area_(kLeft, kTop, std::max(10, canvas.width - kLeft - kRight), std::max(10, canvas.height - kTop - kBottom)),
      x_(Widen(x)),
      y_(Widen(y)) {
  if (equal_scale) {
    const double per_px = std::max((x_.max - x_.min) / area_.width, (y_.max - y_.min) / area_.height);
    const double cx = 0.5 * (x_.min + x_.max), cy = 0.5 * (y_.min + y_.max);
    x_ = {cx - 0.5 * per_px * area_.width, cx + 0.5 * per_px * area_.width};
    y_ = {cy - 0.5 * per_px * area_.height, cy + 0.5 * per_px * area_.height};
  }
}

cv::Point2d PlotAxes::ToPixel(double x, double y) const {
  const double px = area_.x + (x - x_.min) / (x_.max - x_.min) * area_.width;
  const double py = area_.y + area_.height - (y - y_.min) / (y_.max - y_.min) * area_.height;
  return {px, py};
}

cv::Point PlotAxes::ToPixelInt(double x, double y) const {
  const cv::Point2d p = ToPixel(x, y);
  return {static_cast<int>(std::lround(p.x)), static_cast<int>(std::lround(p.y))};
}

cv::Mat PlotAxes::DrawFrame(const std::string& title, const std::string& x_label, const std::string& y_label) const {
  cv::Mat image(canvas_, CV_8UC3, cv::Scalar(255, 255, 255));
  const int bottom = area_.y + area_.height, right = area_.x + area_.width;

  const double x_step = NiceTickStep(x_.max - x_.min, std::max(2, area_.width / 100));
  for (double v = std::ceil(x_.min / x_step) * x_step; v <= x_.max + 1e-9 * x_step; v += x_step) {
    const int px = ToPixelInt(v, y_.min).x;
    cv::line(image, {px, area_.y}, {px, bottom}, kGrid, 1);
    cv::line(image, {px, bottom}, {px, bottom + 5}, kInk, 1);
    PutCentred(image, TickLabel(v, x_step), {px, bottom + 16}, 0.4);
  }
  const double y_step = NiceTickStep(y_.max - y_.min, std::max(2, area_.height / 80));
  for (double v = std::ceil(y_.min / y_step) * y_step; v <= y_.max + 1e-9 * y_step; v += y_step) {
    const int py = ToPixelInt(x_.min, v).y;
    cv::line(image, {area_.x, py}, {right, py}, kGrid, 1);
    cv::line(image, {area_.x - 5, py}, {area_.x, py}, kInk, 1);
    const std::string label = TickLabel(v, y_step);
    int baseline = 0;
    const cv::Size size = cv::getTextSize(label, kFont, 0.4, 1, &baseline);
    cv::putText(image, label, {area_.x - 8 - size.width, py + size.height / 2}, kFont, 0.4, kInk, 1, cv::LINE_AA);
  }
  cv::rectangle(image, area_, kInk, 1);

  PutCentred(image, title, {canvas_.width / 2, kTop / 2}, 0.6);
  PutCentred(image, x_label, {area_.x + area_.width / 2, canvas_.height - 18}, 0.5);
  // The y label, written horizontally then rotated a quarter turn into the left margin.
  int baseline = 0;
  const cv::Size size = cv::getTextSize(y_label, kFont, 0.5, 1, &baseline);
  cv::Mat label(size.height + baseline + 4, size.width + 4, CV_8UC3, cv::Scalar(255, 255, 255));
  cv::putText(label, y_label, {2, size.height + 2}, kFont, 0.5, kInk, 1, cv::LINE_AA);
  cv::Mat rotated;
  cv::rotate(label, rotated, cv::ROTATE_90_COUNTERCLOCKWISE);
  const int x0 = 4;
  const int y0 = std::max(0, area_.y + area_.height / 2 - rotated.rows / 2);
  if (y0 + rotated.rows <= image.rows && x0 + rotated.cols <= image.cols) {
    rotated.copyTo(image(cv::Rect(x0, y0, rotated.cols, rotated.rows)));
  }
  return image;
}

}  // namespace rslam::run
