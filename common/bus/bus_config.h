#pragma once
// How a process joins the bus: vendor, domain, robot, network profile.

#include <string>
#include <vector>

#include "common/config/config_error.h"

namespace rslam::bus {

enum class Vendor { kCyclone, kFastDds };

// "cyclone" or "fastdds"; anything else is a ConfigError naming `key`.
Vendor ParseVendor(const std::string& name, const std::string& key = "bus.dds");
const char* VendorName(Vendor vendor);

struct BusConfig {
  // DDS implementation. The environment variable RSLAM_DDS overrides the config file, and a
  // --dds flag overrides both.
  std::string dds = "cyclone";
  // DDS domain id (0-229). The environment variable RSLAM_DOMAIN overrides the config file.
  int domain_id = 0;
  // This robot's id: the partition its topics are published in and the key of its messages.
  std::string robot_id = "robot1";
  // Network profile: "" = the built-in loopback-only configuration (no multicast, peer
  // 127.0.0.1); otherwise a path to a vendor XML file for real deployments (deploy/dds/).
  std::string cyclone_xml;
  std::string fastdds_xml;

  template <class V>
  void VisitFields(V& v) {
    v("dds", dds, "DDS implementation: cyclone or fastdds (env RSLAM_DDS overrides)");
    v("domain_id", domain_id, "DDS domain id, 0-229 (env RSLAM_DOMAIN overrides)");
    v("robot_id", robot_id, "robot id: topic partition and message key");
    v("cyclone_xml", cyclone_xml, "Cyclone DDS XML for deployments; empty = loopback only");
    v("fastdds_xml", fastdds_xml, "Fast DDS XML (profile rslam_participant); empty = loopback only");
  }
  void Validate() const;

  Vendor vendor() const { return ParseVendor(dds); }
  // Applies RSLAM_DDS and RSLAM_DOMAIN from the environment, then validates.
  void ApplyEnvironment();
};

}  // namespace rslam::bus
