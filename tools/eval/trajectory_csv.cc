#include "tools/eval/trajectory_csv.h"

#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace rslam::eval {

namespace {

std::string Trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string::npos) return {};
  const auto last = s.find_last_not_of(" \t\r");
  return s.substr(first, last - first + 1);
}

std::vector<std::string> SplitFields(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream stream(line);
  std::string field;
  while (std::getline(stream, field, ',')) fields.push_back(Trim(field));
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

[[noreturn]] void Fail(const std::string& source, std::size_t line, const std::string& reason) {
  throw std::runtime_error(source + ":" + std::to_string(line) + ": " + reason);
}

enum Column { kStamp = 0, kX, kY, kTheta, kColumns };
constexpr std::array<const char*, kColumns> kColumnNames = {"stamp_ns", "x", "y", "theta"};

}  // namespace

std::vector<StampedPose2D> ReadTrajectoryCsv(std::istream& in, const std::string& source) {
  std::array<int, kColumns> index;
  index.fill(-1);
  std::size_t field_count = 0;
  bool have_header = false;
  std::vector<StampedPose2D> poses;
  std::string line;
  std::size_t line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const std::string trimmed = Trim(line);
    if (trimmed.empty() || trimmed.front() == '#') continue;
    const std::vector<std::string> fields = SplitFields(trimmed);
    if (!have_header) {
      for (std::size_t f = 0; f < fields.size(); ++f) {
        int column = -1;
        for (int c = 0; c < kColumns; ++c) {
          if (fields[f] == kColumnNames[static_cast<std::size_t>(c)]) column = c;
        }
        if (column < 0) {
          Fail(source, line_number, "unknown column '" + fields[f] + "' in header (expected stamp_ns,x,y[,theta])");
        }
        if (index[static_cast<std::size_t>(column)] >= 0) Fail(source, line_number, "column '" + fields[f] + "' appears twice");
        index[static_cast<std::size_t>(column)] = static_cast<int>(f);
      }
      for (int c = kStamp; c <= kY; ++c) {
        if (index[static_cast<std::size_t>(c)] < 0) {
          Fail(source, line_number, std::string("header lacks column '") + kColumnNames[static_cast<std::size_t>(c)] +
                                        "' (expected stamp_ns,x,y[,theta])");
        }
      }
      field_count = fields.size();
      have_header = true;
      continue;
    }
    if (fields.size() != field_count) {
      Fail(source, line_number, "expected " + std::to_string(field_count) + " fields, got " + std::to_string(fields.size()));
    }
    StampedPose2D pose;
    {
      const std::string& text = fields[static_cast<std::size_t>(index[kStamp])];
      const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), pose.stamp_ns);
      if (error != std::errc() || end != text.data() + text.size()) {
        Fail(source, line_number, "stamp_ns '" + text + "' is not an integer number of nanoseconds");
      }
    }
    auto number = [&](Column c) {
      const std::string& text = fields[static_cast<std::size_t>(index[static_cast<std::size_t>(c)])];
      double value = 0.0;
      const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
      if (error != std::errc() || end != text.data() + text.size() || !std::isfinite(value)) {
        Fail(source, line_number, std::string(kColumnNames[static_cast<std::size_t>(c)]) + " '" + text +
                                      "' is not a finite number");
      }
      return value;
    };
    pose.x = number(kX);
    pose.y = number(kY);
    if (index[kTheta] >= 0) pose.theta = number(kTheta);
    poses.push_back(pose);
  }
  if (!have_header) Fail(source, line_number, "no header line (expected stamp_ns,x,y[,theta])");
  if (poses.empty()) Fail(source, line_number, "no poses after the header");
  return poses;
}

std::vector<StampedPose2D> ReadTrajectoryCsvFile(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw std::runtime_error("cannot open trajectory file '" + path + "'");
  return ReadTrajectoryCsv(file, path);
}

}  // namespace rslam::eval
