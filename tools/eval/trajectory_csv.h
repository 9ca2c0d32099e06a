#pragma once
// Trajectory files of `rslam eval trajectory`: CSV, one pose a line, with a header naming the
// columns, in any order:
//
//   stamp_ns,x,y[,theta]
//   1000000000,0.0,0.0,0.0
//
// stamp_ns: integer nanoseconds (the project's time type); x, y: metres; theta: radians
// (optional column). Blank lines and lines starting with '#' are skipped; other columns are an
// error (so a typo in a header is not silently ignored).

#include <istream>
#include <string>
#include <vector>

#include "tools/eval/trajectory_alignment.h"

namespace rslam::eval {

// Throws std::runtime_error "<source>:<line>: <reason>" for a missing or unknown header column,
// a wrong number of fields, a non-numeric or non-finite value, or no poses at all.
std::vector<StampedPose2D> ReadTrajectoryCsv(std::istream& in, const std::string& source);

// The same from a file (std::runtime_error when it cannot be opened).
std::vector<StampedPose2D> ReadTrajectoryCsvFile(const std::string& path);

}  // namespace rslam::eval
