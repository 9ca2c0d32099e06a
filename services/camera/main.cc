#include "common/node/service_main.h"
#include "services/camera/camera_node.h"

int main(int argc, char** argv) {
  return rslam::RunService<rslam::camera::CameraNode>(
      "camera", "Camera frames (V4L2 device, video file, image folder or the simulator) on camera/image", argc,
      argv);
}
