// Fast DDS back-end of the bus (Fast DDS 2.9 DDS API).
//
// Samples are carried as serialized CDR through a TopicDataType that copies bytes: the type name
// is the IDL's fully qualified name, the payload is the project's XCDR1 bytes, and the key hash
// is the MD5 of the big-endian key fields, the same as the Cyclone back-end computes.

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <fastrtps/utils/md5.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <condition_variable>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>

#include "common/bus/participant.h"

namespace rslam::bus {
namespace {

namespace dds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;
using eprosima::fastrtps::types::ReturnCode_t;

// What Fast DDS hands to the type: bytes to write (view), or a received copy (storage), or, for
// a typed reader (codec set before the take), the message decoded straight from Fast DDS's
// payload (one copy of an image fewer than copying the bytes out, then decoding them).
struct FastDdsSample {
  std::span<const uint8_t> view;
  std::vector<uint8_t> storage;
  const MessageCodec* codec = nullptr;
  DecodedMessage message;
};

class RawTopicDataType final : public dds::TopicDataType {
 public:
  RawTopicDataType(const std::string& name, KeyReader key_reader) : key_reader_(key_reader) {
    setName(name.c_str());
    m_typeSize = 4096;  // initial payload size; payloads grow as needed
    m_isGetKeyDefined = key_reader != nullptr;
  }

  bool serialize(void* data, rtps::SerializedPayload_t* payload) override {
    const auto& view = static_cast<FastDdsSample*>(data)->view;
    if (payload->max_size < view.size()) payload->reserve(static_cast<uint32_t>(view.size()));
    std::memcpy(payload->data, view.data(), view.size());
    payload->length = static_cast<uint32_t>(view.size());
    payload->encapsulation = view.size() >= 2 && view[1] == 0x00 ? CDR_BE : CDR_LE;
    return true;
  }

  bool deserialize(rtps::SerializedPayload_t* payload, void* data) override {
    auto* sample = static_cast<FastDdsSample*>(data);
    sample->message.Reset();
    if (sample->codec != nullptr) {
      try {
        CdrReader reader(std::span<const uint8_t>(payload->data, payload->length));
        sample->message = DecodedMessage(sample->codec->decode(reader), sample->codec);
        sample->storage.clear();
        sample->view = {};
        return true;
      } catch (const CdrError&) {
        // Malformed: hand over the bytes; the typed layer counts and reports them.
      }
    }
    sample->storage.assign(payload->data, payload->data + payload->length);
    sample->view = sample->storage;
    return true;
  }

  std::function<uint32_t()> getSerializedSizeProvider(void* data) override {
    const std::size_t size = static_cast<FastDdsSample*>(data)->view.size();
    return [size] { return static_cast<uint32_t>(size); };
  }

  void* createData() override { return new FastDdsSample(); }
  void deleteData(void* data) override { delete static_cast<FastDdsSample*>(data); }

  bool getKey(void* data, rtps::InstanceHandle_t* handle, bool) override {
    if (key_reader_ == nullptr) return false;
    CdrKeyWriter key;
    try {
      key_reader_(static_cast<FastDdsSample*>(data)->view, key);
    } catch (const CdrError&) {
      // A malformed sample gets the zero key; the typed layer counts and drops it.
      std::memset(handle->value, 0, 16);
      return true;
    }
    ::MD5 md5;
    md5.init();
    md5.update(reinterpret_cast<const char*>(key.bytes().data()), static_cast<unsigned>(key.bytes().size()));
    md5.finalize();
    std::memcpy(handle->value, md5.digest, 16);
    return true;
  }

 private:
  const KeyReader key_reader_;
};

void Check(ReturnCode_t rc, const std::string& what) {
  if (rc != ReturnCode_t::RETCODE_OK) throw BusError("Fast DDS: " + what + " failed (code " + std::to_string(rc()) + ")");
}

template <class Qos>
void ApplyCommonQos(Qos& q, const QosSettings& s) {
  q.reliability().kind = s.reliable ? dds::RELIABLE_RELIABILITY_QOS : dds::BEST_EFFORT_RELIABILITY_QOS;
  q.reliability().max_blocking_time = eprosima::fastrtps::Duration_t(s.max_blocking_ms / 1000,
                                                                     (s.max_blocking_ms % 1000) * 1000000u);
  q.history().kind = s.keep_all ? dds::KEEP_ALL_HISTORY_QOS : dds::KEEP_LAST_HISTORY_QOS;
  q.history().depth = s.depth;
  q.durability().kind = s.transient_local ? dds::TRANSIENT_LOCAL_DURABILITY_QOS : dds::VOLATILE_DURABILITY_QOS;
  // Many robots share a keyed topic: the default of 10 instances is too few. Memory is
  // allocated as samples arrive (dynamic memory policy), so these are caps, not reservations.
  q.resource_limits().max_instances = 64;
  q.resource_limits().max_samples_per_instance = s.keep_all ? 2000 : s.depth;
  q.resource_limits().max_samples = std::min<int32_t>(64 * q.resource_limits().max_samples_per_instance, 50'000'000);
  q.resource_limits().allocated_samples = 16;
  q.endpoint().history_memory_policy = rtps::DYNAMIC_REUSABLE_MEMORY_MODE;
}

class FastDdsWriter final : public RawWriter {
 public:
  FastDdsWriter(dds::DomainParticipant* participant, dds::Publisher* publisher, dds::DataWriter* writer)
      : participant_(participant), publisher_(publisher), writer_(writer) {}
  ~FastDdsWriter() override {
    publisher_->delete_datawriter(writer_);
    participant_->delete_publisher(publisher_);
  }

  void Write(std::span<const uint8_t> cdr) override {
    FastDdsSample sample{cdr, {}, nullptr, {}};
    if (!writer_->write(&sample)) throw BusError("Fast DDS: write failed (a reliable reader did not keep up)");
  }

  int MatchedReaders() const override {
    dds::PublicationMatchedStatus st;
    writer_->get_publication_matched_status(st);
    return st.current_count;
  }

  bool WaitForAcknowledgments(std::chrono::milliseconds timeout) override {
    const auto ms = timeout.count();
    return writer_->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(
               static_cast<int32_t>(ms / 1000), static_cast<uint32_t>((ms % 1000) * 1000000))) ==
           ReturnCode_t::RETCODE_OK;
  }

 private:
  dds::DomainParticipant* const participant_;
  dds::Publisher* const publisher_;
  dds::DataWriter* const writer_;
};

class FastDdsReader final : public RawReader, public dds::DataReaderListener {
 public:
  explicit FastDdsReader(const MessageCodec* codec) : codec_(codec) {}
  ~FastDdsReader() override {
    if (reader_ != nullptr) {
      reader_->set_listener(nullptr);
      subscriber_->delete_datareader(reader_);
      participant_->delete_subscriber(subscriber_);
    }
  }

  void Attach(dds::DomainParticipant* participant, dds::Subscriber* subscriber, dds::DataReader* reader) {
    participant_ = participant;
    subscriber_ = subscriber;
    reader_ = reader;
  }

  void on_data_available(dds::DataReader*) override { Signal(); }

  bool Wait(std::chrono::milliseconds timeout) override {
    std::unique_lock lock(mutex_);
    cv_.wait_for(lock, timeout, [&] { return pending_ || interrupted_; });
    interrupted_ = false;
    return pending_;
  }

  std::size_t Take(std::vector<RawSample>& out, std::size_t max) override {
    {
      std::lock_guard lock(mutex_);
      pending_ = false;
    }
    std::size_t taken = 0;
    FastDdsSample sample;
    sample.codec = codec_;
    dds::SampleInfo info;
    while (taken < max && reader_->take_next_sample(&sample, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      RawSample raw;
      if (sample.message)
        raw.message = std::move(sample.message);
      else
        raw.cdr = std::move(sample.storage);
      raw.source_timestamp_ns = info.source_timestamp.to_ns();
      out.push_back(std::move(raw));
      ++taken;
    }
    if (taken == max) Signal();  // there may be more
    return taken;
  }

  int MatchedWriters() const override {
    dds::SubscriptionMatchedStatus st;
    reader_->get_subscription_matched_status(st);
    return st.current_count;
  }

  void Interrupt() override {
    std::lock_guard lock(mutex_);
    interrupted_ = true;
    cv_.notify_all();
  }

 private:
  void Signal() {
    std::lock_guard lock(mutex_);
    pending_ = true;
    cv_.notify_all();
  }

  const MessageCodec* const codec_;
  dds::DomainParticipant* participant_ = nullptr;
  dds::Subscriber* subscriber_ = nullptr;
  dds::DataReader* reader_ = nullptr;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool pending_ = false;
  bool interrupted_ = false;
};

// Loads the built-in profile once per process, or the deployment's file.
dds::DomainParticipantQos ParticipantQos(const BusConfig& config) {
  static std::mutex mutex;
  static bool builtin_loaded = false;
  std::lock_guard lock(mutex);
  auto* factory = dds::DomainParticipantFactory::get_instance();
  if (config.fastdds_xml.empty()) {
    if (!builtin_loaded) {
      Check(factory->load_XML_profiles_string(kFastDdsLoopbackXml, std::strlen(kFastDdsLoopbackXml)),
            "loading the built-in loopback profile");
      builtin_loaded = true;
    }
  } else {
    Check(factory->load_XML_profiles_file(config.fastdds_xml), "loading " + config.fastdds_xml);
  }
  dds::DomainParticipantQos qos;
  Check(factory->get_participant_qos_from_profile("rslam_participant", qos),
        "profile rslam_participant (in " + (config.fastdds_xml.empty() ? std::string("built-in XML") : config.fastdds_xml) + ")");
  qos.name("rslam/" + config.robot_id);
  return qos;
}

// True if both well-known unicast ports of participant index i are free on 127.0.0.1.
bool IndexIsFree(int domain_id, int index) {
  for (int offset : {10, 11}) {
    const int port = 7400 + 250 * domain_id + offset + 2 * index;
    const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
    if (fd < 0) return false;
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(static_cast<uint16_t>(port));
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    const bool ok = ::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) == 0;
    ::close(fd);
    if (!ok) return false;
  }
  return true;
}

int LowestFreeParticipantIndex(int domain_id) {
  static std::mutex mutex;  // participants of one process start one at a time
  std::lock_guard lock(mutex);
  for (int i = 0; i < 32; ++i)
    if (IndexIsFree(domain_id, i)) return i;
  throw BusError("Fast DDS: no free participant index (0-31) on domain " + std::to_string(domain_id));
}

class FastDdsParticipant final : public Participant {
 public:
  explicit FastDdsParticipant(const BusConfig& config) : Participant(config) {
    // A DEFAULT_FASTRTPS_PROFILES.xml in the working directory must not change the defaults.
    setenv("SKIP_DEFAULT_XML", "1", 0);
    dds::DomainParticipantQos qos = ParticipantQos(config);
    // Fast DDS numbers a process's participants 0, 1, 2, ... and never reuses a number, so a
    // process that re-creates participants would leave the range the peers announce to.
    // Take the lowest free index instead, as Cyclone's ParticipantIndex auto does.
    if (qos.wire_protocol().participant_id < 0)
      qos.wire_protocol().participant_id = LowestFreeParticipantIndex(config.domain_id);
    participant_ = dds::DomainParticipantFactory::get_instance()->create_participant(
        static_cast<dds::DomainId_t>(config.domain_id), qos);
    if (participant_ == nullptr)
      throw BusError("Fast DDS: cannot create participant on domain " + std::to_string(config.domain_id));
  }

  ~FastDdsParticipant() override {
    participant_->delete_contained_entities();
    dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
  }

  std::unique_ptr<RawWriter> CreateRawWriter(const TopicSpec& spec) override {
    dds::Topic* topic = GetTopic(spec);
    dds::PublisherQos pqos;
    pqos.partition().push_back(spec.partition.c_str());
    dds::Publisher* publisher = participant_->create_publisher(pqos);
    if (publisher == nullptr) throw BusError("Fast DDS: cannot create publisher for " + spec.topic);
    dds::DataWriterQos wqos;
    ApplyCommonQos(wqos, SettingsOf(spec.qos));
    wqos.publish_mode().kind = dds::SYNCHRONOUS_PUBLISH_MODE;
    // Acknowledgments come after heartbeats: the 3 s default stalls a keep-all writer whose
    // history is full and delays history to late joiners by up to 3 s.
    wqos.reliable_writer_qos().times.heartbeatPeriod = eprosima::fastrtps::Duration_t(0, 50'000'000);
    // No heartbeats between the fragments of a sample. Cyclone DDS takes the first heartbeat it
    // sees from a writer as the start of the session and drops every sample before its last
    // sequence number that it has not completed, so a heartbeat piggybacked after fragment 3 of
    // 5 lost that image for good (seen: 1 image in 500 at start, in most runs, Fast DDS writer
    // to Cyclone reader). Periodic heartbeats (above) are sent between samples: the writer holds
    // its lock for all fragments of a synchronous write.
    wqos.reliable_writer_qos().disable_heartbeat_piggyback = true;
    wqos.data_sharing().off();
    // XCDR1: what Cyclone DDS 0.10 matches with (an XCDR2 writer does not).
    wqos.representation().m_value = {dds::XCDR_DATA_REPRESENTATION};
    dds::DataWriter* writer = publisher->create_datawriter(topic, wqos);
    if (writer == nullptr) {
      participant_->delete_publisher(publisher);
      throw BusError("Fast DDS: cannot create writer for " + spec.topic);
    }
    return std::make_unique<FastDdsWriter>(participant_, publisher, writer);
  }

  std::unique_ptr<RawReader> CreateRawReader(const TopicSpec& spec) override {
    dds::Topic* topic = GetTopic(spec);
    dds::SubscriberQos sqos;
    sqos.partition().push_back(spec.partition.c_str());
    dds::Subscriber* subscriber = participant_->create_subscriber(sqos);
    if (subscriber == nullptr) throw BusError("Fast DDS: cannot create subscriber for " + spec.topic);
    dds::DataReaderQos rqos;
    ApplyCommonQos(rqos, SettingsOf(spec.qos));
    if (SettingsOf(spec.qos).keep_all) {
      // A keep-all reader whose history is full rejects samples, and Fast DDS 2.9 then stalls
      // the stream (seen: 9,301 of 10,000 to a slow reader). Let the writer's bounded history be
      // the back-pressure instead; reader memory grows only as samples wait.
      rqos.resource_limits().max_samples_per_instance = 100'000;
      rqos.resource_limits().max_samples = 64 * 100'000;
    }
    // Acknowledge at once (default: 5 ms after a heartbeat). A Cyclone DDS writer stops when its
    // unacknowledged data passes its high-water mark (30-500 kB, so after every image) until the
    // acknowledgment: with the default delay a Cyclone camera reached a Fast DDS reader 5 ms late
    // and at most ~300 images/s.
    rqos.reliable_reader_qos().times.heartbeatResponseDelay = eprosima::fastrtps::Duration_t(0, 0);
    rqos.data_sharing().off();
    rqos.type_consistency().representation.m_value = {dds::XCDR_DATA_REPRESENTATION};
    auto reader = std::make_unique<FastDdsReader>(spec.codec);
    dds::DataReader* handle =
        subscriber->create_datareader(topic, rqos, reader.get(), dds::StatusMask::data_available());
    if (handle == nullptr) {
      participant_->delete_subscriber(subscriber);
      throw BusError("Fast DDS: cannot create reader for " + spec.topic);
    }
    reader->Attach(participant_, subscriber, handle);
    return reader;
  }

 private:
  dds::Topic* GetTopic(const TopicSpec& spec) {
    std::lock_guard lock(mutex_);
    auto it = topics_.find(spec.topic);
    if (it != topics_.end()) {
      if (it->second->get_type_name() != spec.type_name)
        throw BusError("topic " + spec.topic + " already has type " + it->second->get_type_name());
      return it->second;
    }
    if (participant_->find_type(spec.type_name).empty()) {
      dds::TypeSupport type(new RawTopicDataType(spec.type_name, spec.key_reader));
      type->auto_fill_type_information(false);
      type->auto_fill_type_object(false);
      Check(type.register_type(participant_), "register type " + spec.type_name);
    }
    dds::Topic* topic = participant_->create_topic(spec.topic, spec.type_name, dds::TOPIC_QOS_DEFAULT);
    if (topic == nullptr) throw BusError("Fast DDS: cannot create topic " + spec.topic);
    topics_[spec.topic] = topic;
    return topic;
  }

  dds::DomainParticipant* participant_ = nullptr;
  std::mutex mutex_;
  std::map<std::string, dds::Topic*> topics_;
};

}  // namespace

std::unique_ptr<Participant> CreateFastDdsParticipant(const BusConfig& config) {
  return std::make_unique<FastDdsParticipant>(config);
}

}  // namespace rslam::bus
