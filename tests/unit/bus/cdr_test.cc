// The XCDR1 encoding, byte for byte, against hand-computed buffers.

#include <gtest/gtest.h>

#include "common/bus/typed_cdr.h"
#include "rslam/msg/all_messages.h"

namespace rslam::bus {
namespace {

TEST(CdrTest, VelocityEncodesAsXcdr1LittleEndianWithAlignment) {
  msg::Velocity v;
  v.header = {"ab", 1, -2};
  v.vtrans_mps = 1.5;
  v.vrot_radps = 0;
  v.dt_s = 0;
  v.source = msg::VelocitySource::VELOCITY_WHEEL;
  v.wall_seen = true;
  v.wall_direction_rad = -0.25;
  v.boundary_measured = true;
  v.boundary = {{0.5f, -1.0f}};
  const std::vector<uint8_t> cdr = ToCdr(v);
  const std::vector<uint8_t> expected = {
      0x00, 0x01, 0x00, 0x00,                          // encapsulation CDR_LE
      0x03, 0x00, 0x00, 0x00, 'a', 'b', 0x00,          // string "ab" with NUL
      0x00,                                            // pad to 8 (offset 8 after header)
      0x01, 0, 0, 0, 0, 0, 0, 0,                        // frame_seq
      0xFE, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF,  // stamp_ns = -2
      0, 0, 0, 0, 0, 0, 0xF8, 0x3F,                    // 1.5
      0, 0, 0, 0, 0, 0, 0, 0,                          // 0.0
      0, 0, 0, 0, 0, 0, 0, 0,                          // 0.0
      0x01, 0, 0, 0,                                   // enum VELOCITY_WHEEL
      0x01, 0, 0, 0,                                   // true, padded to 8
      0, 0, 0, 0, 0, 0, 0xD0, 0xBF,                    // -0.25
      0x01, 0, 0, 0,                                   // true, padded to 4 for the count
      0x01, 0, 0, 0,                                   // one boundary point
      0, 0, 0, 0x3F, 0, 0, 0x80, 0xBF,                 // (0.5f, -1.0f)
  };
  EXPECT_EQ(cdr, expected);
  EXPECT_EQ(FromCdr<msg::Velocity>(cdr), v);
}

TEST(CdrTest, MessagesArePaddedToFourBytesAndSaySo) {
  msg::Header h{"abc", 1, 2};  // 4 + 4 + 4 + 8 + 8 = 28 bytes with the header: no padding
  msg::ViewTemplate v;
  v.header.robot_id = "ab";  // ... + uint32 template_count at the end: 4 + 4+3+1 + 8+8 + 4+1+3 + 8+8 + 4 = 56
  const auto cdr = ToCdr(v);
  EXPECT_EQ(cdr.size() % 4, 0u);
  msg::Image image;
  image.encoding = "m";
  image.data = {1, 2, 3, 4, 5};  // ends 5 bytes after an aligned count: 3 bytes of padding
  const auto img = ToCdr(image);
  EXPECT_EQ(img.size() % 4, 0u);
  EXPECT_EQ(img[3], 3);
  EXPECT_EQ(FromCdr<msg::Image>(img), image);
  (void)h;
}

TEST(CdrTest, KeyIsTheBigEndianRobotId) {
  msg::ServiceStatus s;
  s.header.robot_id = "r1";
  s.service = "odo";
  CdrKeyWriter key;
  ReadKey<msg::ServiceStatus>(ToCdr(s), key);
  const std::vector<uint8_t> expected = {0, 0, 0, 3, 'r', '1', 0, 0, 0, 0, 0, 4, 'o', 'd', 'o', 0};
  EXPECT_EQ(key.bytes(), expected);
}

TEST(CdrTest, BigEndianInputDecodes) {
  // Header alone, encoded big-endian by hand: robot "x", frame 258, stamp 1.
  const std::vector<uint8_t> be = {0x00, 0x00, 0x00, 0x00, 0, 0, 0, 2, 'x', 0, 0, 0,
                                   0, 0, 0, 0, 0, 0, 1, 2, 0, 0, 0, 0, 0, 0, 0, 1};
  CdrReader reader(be);
  msg::Header h;
  Deserialize(reader, h);
  EXPECT_EQ(h.robot_id, "x");
  EXPECT_EQ(h.frame_seq, 258u);
  EXPECT_EQ(h.stamp_ns, 1);
}

TEST(CdrTest, TruncatedOrCorruptMessagesAreRefused) {
  msg::Image image;
  FillExample(image, 1);
  std::vector<uint8_t> cdr = ToCdr(image);
  const std::size_t padding = cdr[3] & 3;
  for (std::size_t cut : {std::size_t{0}, std::size_t{3}, std::size_t{10}, cdr.size() - padding - 1}) {
    std::vector<uint8_t> part(cdr.begin(), cdr.begin() + static_cast<long>(cut));
    EXPECT_THROW(FromCdr<msg::Image>(part), CdrError) << "cut at " << cut;
  }
  // A sequence count far beyond the buffer must not allocate.
  std::vector<uint8_t> huge = cdr;
  const std::size_t count_at = huge.size() - padding - image.data.size() - 4;
  huge[count_at + 3] = 0x7F;
  EXPECT_THROW(FromCdr<msg::Image>(huge), CdrError);
  // An unknown enum value is refused.
  msg::Velocity v;
  std::vector<uint8_t> vel = ToCdr(v);
  vel[vel.size() - 24] = 9;  // the enum, before bool, padding, double, bool, padding, count
  EXPECT_THROW(FromCdr<msg::Velocity>(vel), CdrError);
  // XCDR2 or parameter-list encodings are refused.
  std::vector<uint8_t> xcdr2 = cdr;
  xcdr2[1] = 0x07;
  EXPECT_THROW(FromCdr<msg::Image>(xcdr2), CdrError);
}

// Cyclone hands a received sample over as network fragments; the reader decodes them without
// joining them first. Every cut (inside the header, a string, a number, the pixels) must decode
// to the same message, and a truncated last piece must still be refused.
TEST(CdrTest, MessageInPiecesDecodesAsTheWhole) {
  msg::Image image;
  image.header = {"robot7", 99, -5};
  image.width = 8;
  image.height = 4;
  image.encoding = "mono8";
  image.step = 8;
  image.data.resize(32);
  for (std::size_t i = 0; i < image.data.size(); ++i) image.data[i] = static_cast<uint8_t>(i * 13 + 1);
  const std::vector<uint8_t> cdr = ToCdr(image);
  const std::span<const uint8_t> all(cdr);
  for (std::size_t a = 1; a < cdr.size(); ++a) {
    for (std::size_t b : {a, std::min(cdr.size(), a + 3), std::min(cdr.size(), a + 17)}) {
      const std::span<const uint8_t> pieces[] = {all.subspan(0, a), all.subspan(a, b - a), all.subspan(b)};
      CdrReader reader{std::span<const std::span<const uint8_t>>(pieces)};
      msg::Image got;
      Deserialize(reader, got);
      EXPECT_EQ(got, image) << "cut at " << a << " and " << b;
    }
    const std::span<const uint8_t> truncated[] = {all.subspan(0, a), all.subspan(a, cdr.size() - a - 4 - 1)};
    if (a < cdr.size() - 5) {
      CdrReader reader{std::span<const std::span<const uint8_t>>(truncated)};
      msg::Image got;
      EXPECT_THROW(Deserialize(reader, got), CdrError) << "cut at " << a;
    }
  }
}

// A message decoded into one that already holds a larger image keeps no stale bytes.
TEST(CdrTest, DecodingIntoAUsedMessageReplacesEverything) {
  msg::Image small;
  FillExample(small, 2);
  msg::Image big;
  FillExample(big, 3);
  big.data.assign(1000, 7);
  const std::vector<uint8_t> cdr = ToCdr(small);
  CdrReader reader(cdr);
  Deserialize(reader, big);
  EXPECT_EQ(big, small);
}

}  // namespace
}  // namespace rslam::bus
