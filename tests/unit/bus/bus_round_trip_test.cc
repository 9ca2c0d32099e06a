// Typed and raw round trips on each vendor and across vendors (tests named ...Interop).

#include <gtest/gtest.h>

#include <chrono>
#include <numeric>

#include "common/bus/message_registry.h"
#include "common/bus/publisher.h"
#include "common/bus/subscriber.h"
#include "tests/unit/bus/bus_test_util.h"

namespace rslam::bus {
namespace {

using namespace std::chrono_literals;

// "rslam::msg::Image" -> "test/Image" (DDS topic names allow letters, digits, _ and /).
inline std::string TopicNameFor(std::string type) { return "test/" + type.substr(type.rfind(':') + 1); }

template <class T>
struct RoundTripCase {
  RoundTripCase(Participant& w, Participant& r)
      : topic(TopicNameFor(MessageTraits<T>::kTypeName)),
        publisher(w, Topic<T>{topic, QosPreset::kState}),
        subscriber(r, Topic<T>{topic, QosPreset::kState}) {
    FillExample(sent, 11);
  }
  bool Matched() { return publisher.MatchedSubscribers() >= 1 && subscriber.MatchedPublishers() >= 1; }
  std::string topic;
  Publisher<T> publisher;
  Subscriber<T> subscriber;
  T sent;
};

TEST_P(BusTest, EveryMessageTypeRoundTrips) {
  auto writer = MakeWriter();
  auto reader = MakeReader();
#define RSLAM_CASE(Type) RoundTripCase<msg::Type> case_##Type(*writer, *reader);
  RSLAM_FOR_EACH_MESSAGE(RSLAM_CASE)
#undef RSLAM_CASE
  int types = 0;
#define RSLAM_CHECK(Type)                                                             \
  {                                                                                   \
    ++types;                                                                          \
    case_##Type.publisher.Publish(case_##Type.sent);                                  \
    auto got = case_##Type.subscriber.TakeOne(10s);                                  \
    ASSERT_TRUE(got.has_value()) << #Type << " not received";                         \
    EXPECT_TRUE(*got == case_##Type.sent) << #Type << " differs after the round trip"; \
  }
  RSLAM_FOR_EACH_MESSAGE(RSLAM_CHECK)
#undef RSLAM_CHECK
  EXPECT_EQ(types, static_cast<int>(AllMessageTypes().size()));
}

TEST_P(BusTest, Image640x480ArrivesIntact) {
  auto writer = MakeWriter();
  auto reader = MakeReader();
  Publisher<msg::Image> pub(*writer, topics::kCameraImage);
  Subscriber<msg::Image> sub(*reader, topics::kCameraImage);
  ASSERT_TRUE(pub.WaitForSubscribers(1, 10s));
  ASSERT_TRUE(sub.WaitForPublishers(1, 10s));
  msg::Image image;
  image.header = {"robot1", 42, 1'700'000'000'000'000'000};
  image.width = 640;
  image.height = 480;
  image.encoding = "mono8";
  image.step = 640;
  image.data.resize(640 * 480);
  for (std::size_t i = 0; i < image.data.size(); ++i) image.data[i] = static_cast<uint8_t>((i * 31) ^ (i >> 9));
  pub.Publish(image);
  auto got = sub.TakeOne(10s);
  ASSERT_TRUE(got.has_value());
  EXPECT_EQ(got->header, image.header);
  EXPECT_EQ(got->data, image.data);
}

// Typed readers may get images decoded by the vendor as they arrive; readers of the same topic in
// the same participant must still each get the whole image: a second typed reader (the sample is
// shared, so neither may take it from the other) and a raw reader (bytes, as the recorder).
TEST_P(BusTest, ImageReachesTwoTypedReadersAndARawReaderOfOneParticipant) {
  auto writer = MakeWriter();
  auto reader = MakeReader();
  Publisher<msg::Image> pub(*writer, topics::kCameraImage);
  Subscriber<msg::Image> first(*reader, topics::kCameraImage);
  Subscriber<msg::Image> second(*reader, topics::kCameraImage);
  auto raw = reader->CreateRawReader(TopicSpec{"camera/image", "rslam::msg::Image", KeyReaderFor<msg::Image>(),
                                               topics::kCameraImage.qos, "robot1"});
  ASSERT_TRUE(pub.WaitForSubscribers(3, 10s));
  ASSERT_TRUE(first.WaitForPublishers(1, 10s));
  ASSERT_TRUE(second.WaitForPublishers(1, 10s));
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (raw->MatchedWriters() < 1 && std::chrono::steady_clock::now() < deadline) raw->Wait(10ms);
  msg::Image image;
  image.header = {"robot1", 7, 123};
  image.width = 640;
  image.height = 480;
  image.encoding = "mono8";
  image.step = 640;
  image.data.resize(640 * 480);
  for (std::size_t i = 0; i < image.data.size(); ++i) image.data[i] = static_cast<uint8_t>((i * 17) ^ (i >> 11));
  pub.Publish(image);
  std::vector<RawSample> samples;
  while (samples.empty() && std::chrono::steady_clock::now() < deadline) {
    raw->Wait(100ms);
    raw->Take(samples, 10);
  }
  ASSERT_EQ(samples.size(), 1u);
  EXPECT_FALSE(samples[0].message);
  EXPECT_EQ(samples[0].cdr, ToCdr(image));
  for (Subscriber<msg::Image>* sub : {&first, &second}) {
    auto got = sub->TakeOne(10s);
    ASSERT_TRUE(got.has_value());
    EXPECT_EQ(*got, image);
  }
}

TEST_P(BusTest, RawCdrTakenDecodesToTheTypedMessage) {
  auto writer = MakeWriter();
  auto reader = MakeReader();
  Publisher<msg::Velocity> pub(*writer, topics::kOdometryVelocity);
  auto raw = reader->CreateRawReader(TopicSpec{"odometry/velocity", "rslam::msg::Velocity",
                                               KeyReaderFor<msg::Velocity>(), QosPreset::kStream, "robot1"});
  ASSERT_TRUE(pub.WaitForSubscribers(1, 10s));
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (raw->MatchedWriters() < 1 && std::chrono::steady_clock::now() < deadline) raw->Wait(10ms);
  msg::Velocity v;
  FillExample(v, 3);
  pub.Publish(v);
  std::vector<RawSample> samples;
  while (samples.empty() && std::chrono::steady_clock::now() < deadline) {
    raw->Wait(100ms);
    raw->Take(samples, 10);
  }
  ASSERT_EQ(samples.size(), 1u);
  EXPECT_EQ(samples[0].cdr, ToCdr(v));
  EXPECT_EQ(FromCdr<msg::Velocity>(samples[0].cdr), v);
}

TEST_P(BusTest, RawPublishIsReceivedTyped) {
  auto writer = MakeWriter();
  auto reader = MakeReader();
  auto raw = writer->CreateRawWriter(TopicSpec{"templates/view", "rslam::msg::ViewTemplate",
                                               KeyReaderFor<msg::ViewTemplate>(), QosPreset::kStream, "robot1"});
  Subscriber<msg::ViewTemplate> sub(*reader, topics::kTemplatesView);
  ASSERT_TRUE(sub.WaitForPublishers(1, 10s));
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (raw->MatchedReaders() < 1 && std::chrono::steady_clock::now() < deadline) sub.Wait(10ms);
  msg::ViewTemplate view;
  FillExample(view, 5);
  raw->Write(ToCdr(view));
  auto got = sub.TakeOne(10s);
  ASSERT_TRUE(got.has_value());
  EXPECT_EQ(*got, view);
}

TEST_P(BusTest, MalformedMessageIsCountedAndDroppedWhileGoodOnesFlow) {
  auto writer = MakeWriter();
  auto reader = MakeReader();
  auto raw = writer->CreateRawWriter(TopicSpec{"templates/view", "rslam::msg::ViewTemplate",
                                               KeyReaderFor<msg::ViewTemplate>(), QosPreset::kStream, "robot1"});
  Subscriber<msg::ViewTemplate> sub(*reader, topics::kTemplatesView);
  ASSERT_TRUE(sub.WaitForPublishers(1, 10s));
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (raw->MatchedReaders() < 1 && std::chrono::steady_clock::now() < deadline) sub.Wait(10ms);
  msg::ViewTemplate view;
  FillExample(view, 9);
  std::vector<uint8_t> truncated = ToCdr(view);
  truncated.resize(truncated.size() - 12);  // the key (robot id) survives, the body does not
  raw->Write(truncated);
  raw->Write(ToCdr(view));
  auto got = sub.TakeOne(10s);
  ASSERT_TRUE(got.has_value());
  EXPECT_EQ(*got, view);
  EXPECT_EQ(sub.rejected(), 1u);
}

INSTANTIATE_TEST_SUITE_P(Vendors, BusTest, kAllPairs, PairName);

}  // namespace
}  // namespace rslam::bus
