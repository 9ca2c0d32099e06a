#pragma once
// The one time type of the project. Stamps are nanoseconds of the time a camera frame was
// taken (the source stamp), carried unchanged through every message; algorithms compute dt
// from stamps, never from the wall clock.

#include <chrono>
#include <cstdint>

namespace rslam {

using Duration = std::chrono::nanoseconds;
using Time = std::chrono::time_point<std::chrono::system_clock, Duration>;

inline Time TimeFromNanoseconds(int64_t ns) { return Time(Duration(ns)); }
inline int64_t ToNanoseconds(Time t) { return t.time_since_epoch().count(); }
inline double ToSeconds(Duration d) { return std::chrono::duration<double>(d).count(); }
inline Duration FromSeconds(double s) {
  return std::chrono::duration_cast<Duration>(std::chrono::duration<double>(s));
}
// Wall clock: only for stamping frames at capture and for heartbeats, never inside algorithms.
inline Time WallNow() { return std::chrono::time_point_cast<Duration>(std::chrono::system_clock::now()); }

}  // namespace rslam
