#pragma once
// Frames of a robot driving a closed loop, written as PNG files for the camera service and the
// runner: places_per_lap places, each frame the camera turns 360/places_per_lap degrees and moves
// forward, so frame i and frame i + places_per_lap are the same image (the place is recognised
// and the loop closes). 160x120 grey, three 40-row bands, one per stage
// (synthetic_loop_160x120.yaml):
//   rows  0-40   a textured panorama scrolled 5 px per frame: visual odometry's rotation
//   rows 40-80   a texture unique to the place: the template library
//   rows 80-120  noise unique to the place: its change between frames is the odometry's speed

#include <opencv2/core.hpp>

#include <filesystem>
#include <string>

namespace rslam::system_test {

inline constexpr int kLoopFrameWidth = 160;
inline constexpr int kLoopFrameHeight = 120;

// Frame `index` of the loop (CV_8UC1).
cv::Mat LoopFrame(int places_per_lap, int index);

// Writes frames 0..frames-1 as folder/frame_00000.png, ... (name order = frame order).
void WriteLoopFrames(const std::filesystem::path& folder, int places_per_lap, int frames);

}  // namespace rslam::system_test
