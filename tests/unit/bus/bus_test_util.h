#pragma once
// Shared set-up of the bus tests: participants of either vendor on the test's private domain.

#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "common/bus/participant.h"
#include "tests/support/test_domain.h"

namespace rslam::bus {

struct VendorPair {
  Vendor writer;
  Vendor reader;
};

inline std::string PairName(const ::testing::TestParamInfo<VendorPair>& info) {
  const auto name = [](Vendor v) { return v == Vendor::kCyclone ? std::string("Cyclone") : std::string("FastDds"); };
  if (info.param.writer == info.param.reader) return name(info.param.writer);
  return name(info.param.writer) + "To" + name(info.param.reader) + "Interop";
}

inline const auto kAllPairs = ::testing::Values(VendorPair{Vendor::kCyclone, Vendor::kCyclone},
                                                VendorPair{Vendor::kFastDds, Vendor::kFastDds},
                                                VendorPair{Vendor::kCyclone, Vendor::kFastDds},
                                                VendorPair{Vendor::kFastDds, Vendor::kCyclone});

class BusTest : public ::testing::TestWithParam<VendorPair> {
 protected:
  std::unique_ptr<Participant> Make(Vendor vendor, const std::string& robot = "robot1") {
    BusConfig config;
    config.dds = VendorName(vendor);
    config.domain_id = domain_.id();
    config.robot_id = robot;
    return Participant::Create(config);
  }
  std::unique_ptr<Participant> MakeWriter(const std::string& robot = "robot1") { return Make(GetParam().writer, robot); }
  std::unique_ptr<Participant> MakeReader(const std::string& robot = "robot1") { return Make(GetParam().reader, robot); }

  testing::TestDomain domain_;
};

}  // namespace rslam::bus
