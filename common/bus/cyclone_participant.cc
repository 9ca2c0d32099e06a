// Cyclone DDS back-end of the bus (Cyclone DDS 0.10 C API).
//
// Samples are carried as serialized CDR through a custom sertype (as cyclonedds-cxx and ROS 2's
// rmw_cyclonedds do): the type name is the IDL's fully qualified name, the payload is the
// project's XCDR1 bytes, and the instance key hash is the MD5 of the big-endian key fields, as
// DDS specifies, so instances agree with Fast DDS.
//
// Large messages make every pass over their bytes count (a 640x480 image is 307 KB):
//   - a typed publisher serializes into a buffer that the serdata then owns (no copy), and the
//     buffers come back to a small pool of the topic's sertype when Cyclone frees the serdata;
//   - a topic created by a typed subscriber (TopicSpec::codec) decodes each received sample
//     straight from Cyclone's receive buffers (the fragments, not joined first) into the message
//     the subscriber will take: one copy after the kernel's, as few as Cyclone's own typed path
//     (which joins the fragments into its serdata, then deserializes into the application's
//     sample). Readers without a codec (recorder) get bytes: on such a topic, re-encoded from
//     the message (the same bytes for any well-formed little-endian sender; publishers pass
//     no codec, so a recorder's own status publisher leaves its topics byte-exact).

#include <dds/dds.h>
#include <dds/ddsi/ddsi_serdata.h>
#include <dds/ddsi/ddsi_sertype.h>
#include <dds/ddsi/q_radmin.h>
#include <dds/ddsrt/md5.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstring>
#include <map>
#include <mutex>
#include <new>

#include "common/bus/participant.h"

namespace rslam::bus {
namespace {

// Spare serialization buffers of one topic: written samples' buffers come back here when
// Cyclone frees them (after the readers acknowledged them), for the next Publish.
class BufferPool {
 public:
  std::vector<uint8_t> Acquire() {
    std::lock_guard lock(mutex_);
    if (spare_.empty()) return {};
    std::vector<uint8_t> buffer = std::move(spare_.back());
    spare_.pop_back();
    return buffer;
  }
  void Release(std::vector<uint8_t>&& buffer) {
    if (buffer.capacity() < kMinPooledBytes) return;  // small ones are cheap to allocate
    std::lock_guard lock(mutex_);
    if (spare_.size() < kMaxSpare) spare_.push_back(std::move(buffer));
  }

 private:
  static constexpr std::size_t kMinPooledBytes = 16 * 1024;
  static constexpr std::size_t kMaxSpare = 4;
  std::mutex mutex_;
  std::vector<std::vector<uint8_t>> spare_;
};

struct RawSertype {
  ddsi_sertype base;  // first: Cyclone sees only this
  KeyReader key_reader;
  const MessageCodec* codec;  // null: samples stay bytes
  BufferPool pool;
};

struct RawSerdata {
  ddsi_serdata base;  // first
  std::vector<uint8_t> bytes;  // CDR with encapsulation header, zero-padded to a multiple of 4
  uint32_t size = 0;           // CDR size without the padding
  ddsi_keyhash_t keyhash{};
  // A received sample decoded on arrival (typed topics) has no bytes until someone asks for
  // them (EncodedBytes).
  DecodedMessage message;
  std::once_flag encoded;
};

const RawSertype* AsRawType(const ddsi_sertype* t) { return reinterpret_cast<const RawSertype*>(t); }
const RawSerdata* AsRaw(const ddsi_serdata* d) { return reinterpret_cast<const RawSerdata*>(d); }
RawSerdata* AsRaw(ddsi_serdata* d) { return reinterpret_cast<RawSerdata*>(d); }

// Cyclone's sample type for dds_take (unused by the bus, which takes serdata directly).
struct CycloneSample {
  std::vector<uint8_t> cdr;
};

uint32_t HashKey(const ddsi_keyhash_t& kh) {
  uint32_t h = 2166136261u;
  for (uint8_t b : kh.value) h = (h ^ b) * 16777619u;
  return h;
}

void ComputeKeyHash(RawSerdata* d, const RawSertype* type) {
  std::memset(d->keyhash.value, 0, sizeof(d->keyhash.value));
  if (type->key_reader != nullptr && d->size > 0) {
    CdrKeyWriter key;
    type->key_reader(std::span<const uint8_t>(d->bytes.data(), d->size), key);
    ddsrt_md5_state_t md5;
    ddsrt_md5_init(&md5);
    ddsrt_md5_append(&md5, key.bytes().data(), static_cast<uint32_t>(key.bytes().size()));
    ddsrt_md5_finish(&md5, d->keyhash.value);
  }
  d->base.hash = HashKey(d->keyhash) ^ type->base.serdata_basehash;
}

std::size_t PaddedSize(std::size_t size) { return (size + 3) & ~std::size_t{3}; }

// An empty serdata with room for size bytes; the caller appends them, then calls Pad. (Images
// make every pass over the bytes count: no zero-filling of what is overwritten at once.)
RawSerdata* NewSerdata(const ddsi_sertype* type, ddsi_serdata_kind kind, std::size_t size) {
  auto* d = new RawSerdata();
  if (size >= 16 * 1024) d->bytes = const_cast<RawSertype*>(AsRawType(type))->pool.Acquire();
  ddsi_serdata_init(&d->base, type, kind);
  d->size = static_cast<uint32_t>(size);
  d->bytes.clear();
  d->bytes.reserve(PaddedSize(size));
  return d;
}

// Zero padding to a multiple of 4 (and zeros for anything the source did not cover).
void Pad(RawSerdata* d) { d->bytes.resize(PaddedSize(d->size)); }

RawSerdata* NewSerdataFrom(const ddsi_sertype* type, ddsi_serdata_kind kind, std::span<const uint8_t> bytes) {
  RawSerdata* d = NewSerdata(type, kind, bytes.size());
  d->bytes.assign(bytes.begin(), bytes.end());
  Pad(d);
  return d;
}

// A serdata from received bytes; null when the bytes are malformed (Cyclone then drops them).
ddsi_serdata* Finish(RawSerdata* d, const ddsi_sertype* type) {
  try {
    ComputeKeyHash(d, AsRawType(type));
  } catch (const CdrError&) {
    if (d->base.kind == SDK_DATA) {
      // Keep a malformed data sample with a zero key so the typed layer can count and report it.
      std::memset(d->keyhash.value, 0, sizeof(d->keyhash.value));
      d->base.hash = HashKey(d->keyhash) ^ type->serdata_basehash;
      return &d->base;
    }
    delete d;
    return nullptr;
  }
  return &d->base;
}

bool SerdataEqKey(const ddsi_serdata* a, const ddsi_serdata* b) {
  return std::memcmp(AsRaw(a)->keyhash.value, AsRaw(b)->keyhash.value, 16) == 0;
}

uint32_t SerdataSize(const ddsi_serdata* d) { return AsRaw(d)->size; }

// The payload of a received sample as Cyclone holds it: fragments in order, possibly overlapping,
// cut to back-to-back pieces. False if there are more than fit (then the caller joins them).
bool CollectFragments(const nn_rdata* fragchain, size_t size, std::vector<std::span<const uint8_t>>& pieces) {
  uint32_t off = 0;
  for (; fragchain != nullptr; fragchain = fragchain->nextfrag) {
    const uint32_t end = std::min<uint32_t>(fragchain->maxp1, static_cast<uint32_t>(size));
    if (end <= off) continue;
    const unsigned char* payload = NN_RMSG_PAYLOADOFF(fragchain->rmsg, NN_RDATA_PAYLOAD_OFF(fragchain));
    pieces.emplace_back(payload + (off - fragchain->min), end - off);
    off = end;
  }
  return off == size;
}

// A typed topic's data sample decoded straight from the fragments, or null (not a typed topic,
// malformed, or the key not within the first fragment: the caller keeps bytes instead).
RawSerdata* DecodeFromFragments(const ddsi_sertype* type, ddsi_serdata_kind kind, const nn_rdata* fragchain,
                                size_t size) {
  const RawSertype* raw_type = AsRawType(type);
  if (raw_type->codec == nullptr || kind != SDK_DATA) return nullptr;
  thread_local std::vector<std::span<const uint8_t>> pieces;
  pieces.clear();
  if (!CollectFragments(fragchain, size, pieces) || pieces.empty()) return nullptr;
  auto* d = new RawSerdata();
  ddsi_serdata_init(&d->base, type, kind);
  d->size = static_cast<uint32_t>(size);
  try {
    CdrReader reader{std::span<const std::span<const uint8_t>>(pieces)};
    d->message = DecodedMessage(raw_type->codec->decode(reader), raw_type->codec);
    if (raw_type->key_reader != nullptr) {
      CdrKeyWriter key;
      raw_type->key_reader(pieces.front(), key);
      ddsrt_md5_state_t md5;
      ddsrt_md5_init(&md5);
      ddsrt_md5_append(&md5, key.bytes().data(), static_cast<uint32_t>(key.bytes().size()));
      ddsrt_md5_finish(&md5, d->keyhash.value);
    }
  } catch (const CdrError&) {
    delete d;
    return nullptr;
  }
  d->base.hash = HashKey(d->keyhash) ^ type->serdata_basehash;
  return d;
}

// The bytes of a sample, encoded from its decoded message on first use.
const std::vector<uint8_t>& EncodedBytes(const ddsi_serdata* serdata) {
  auto* d = const_cast<RawSerdata*>(AsRaw(serdata));
  std::call_once(d->encoded, [d] {
    if (!d->message || !d->bytes.empty()) return;
    d->message.codec()->encode(d->message.get(), d->bytes);
    d->size = static_cast<uint32_t>(d->bytes.size());
    Pad(d);
  });
  return d->bytes;
}

ddsi_serdata* SerdataFromSer(const ddsi_sertype* type, ddsi_serdata_kind kind, const nn_rdata* fragchain,
                             size_t size) {
  if (RawSerdata* decoded = DecodeFromFragments(type, kind, fragchain, size)) return &decoded->base;
  RawSerdata* d = NewSerdata(type, kind, size);
  // The fragments come in order and may overlap: append the part of each beyond what we have.
  uint32_t off = 0;
  for (; fragchain != nullptr; fragchain = fragchain->nextfrag) {
    const uint32_t end = std::min<uint32_t>(fragchain->maxp1, static_cast<uint32_t>(size));
    if (end <= off) continue;
    const unsigned char* payload = NN_RMSG_PAYLOADOFF(fragchain->rmsg, NN_RDATA_PAYLOAD_OFF(fragchain));
    d->bytes.insert(d->bytes.end(), payload + (off - fragchain->min), payload + (end - fragchain->min));
    off = end;
  }
  Pad(d);
  return Finish(d, type);
}

ddsi_serdata* SerdataFromSerIov(const ddsi_sertype* type, ddsi_serdata_kind kind, ddsrt_msg_iovlen_t niov,
                                const ddsrt_iovec_t* iov, size_t size) {
  RawSerdata* d = NewSerdata(type, kind, size);
  for (ddsrt_msg_iovlen_t i = 0; i < niov && d->bytes.size() < size; ++i) {
    const auto* base = static_cast<const uint8_t*>(iov[i].iov_base);
    d->bytes.insert(d->bytes.end(), base, base + std::min<std::size_t>(iov[i].iov_len, size - d->bytes.size()));
  }
  Pad(d);
  return Finish(d, type);
}

ddsi_serdata* SerdataFromKeyhash(const ddsi_sertype* type, const ddsi_keyhash* keyhash) {
  RawSerdata* d = NewSerdata(type, SDK_KEY, 0);
  std::memcpy(d->keyhash.value, keyhash->value, 16);
  d->base.hash = HashKey(d->keyhash) ^ type->serdata_basehash;
  return &d->base;
}

ddsi_serdata* SerdataFromSample(const ddsi_sertype* type, ddsi_serdata_kind kind, const void* sample) {
  const auto* s = static_cast<const CycloneSample*>(sample);
  RawSerdata* d = NewSerdataFrom(type, kind, s->cdr);
  try {
    ComputeKeyHash(d, AsRawType(type));
  } catch (const CdrError&) {
    delete d;
    return nullptr;
  }
  return &d->base;
}

void SerdataToSer(const ddsi_serdata* d, size_t off, size_t sz, void* buf) {
  const std::vector<uint8_t>& bytes = EncodedBytes(d);
  const std::size_t avail = off < bytes.size() ? bytes.size() - off : 0;
  std::memcpy(buf, bytes.data() + off, std::min(sz, avail));
  if (sz > avail) std::memset(static_cast<char*>(buf) + avail, 0, sz - avail);
}

ddsi_serdata* SerdataToSerRef(const ddsi_serdata* d, size_t off, size_t sz, ddsrt_iovec_t* ref) {
  ref->iov_base = const_cast<uint8_t*>(EncodedBytes(d).data() + off);
  ref->iov_len = static_cast<ddsrt_iov_len_t>(sz);
  return ddsi_serdata_ref(d);
}

void SerdataToSerUnref(ddsi_serdata* d, const ddsrt_iovec_t*) { ddsi_serdata_unref(d); }

bool SerdataToSample(const ddsi_serdata* d, void* sample, void**, void*) {
  const std::vector<uint8_t>& bytes = EncodedBytes(d);
  static_cast<CycloneSample*>(sample)->cdr.assign(bytes.begin(), bytes.begin() + AsRaw(d)->size);
  return true;
}

ddsi_serdata* SerdataToUntyped(const ddsi_serdata* d) {
  RawSerdata* u = NewSerdata(d->type, SDK_KEY, 0);
  std::memcpy(u->keyhash.value, AsRaw(d)->keyhash.value, 16);
  u->base.hash = d->hash;
  u->base.type = nullptr;
  return &u->base;
}

bool UntypedToSample(const ddsi_sertype*, const ddsi_serdata*, void* sample, void**, void*) {
  if (sample != nullptr) static_cast<CycloneSample*>(sample)->cdr.clear();
  return true;
}

void SerdataFree(ddsi_serdata* d) {
  RawSerdata* r = AsRaw(d);
  if (d->type != nullptr) const_cast<RawSertype*>(AsRawType(d->type))->pool.Release(std::move(r->bytes));
  delete r;
}

size_t SerdataPrint(const ddsi_sertype*, const ddsi_serdata* d, char* buf, size_t size) {
  return static_cast<size_t>(std::snprintf(buf, size, "cdr(%u bytes)", AsRaw(d)->size));
}

void SerdataGetKeyhash(const ddsi_serdata* d, ddsi_keyhash* buf, bool) {
  std::memcpy(buf->value, AsRaw(d)->keyhash.value, 16);
}

const ddsi_serdata_ops kSerdataOps = {
    .eqkey = SerdataEqKey,
    .get_size = SerdataSize,
    .from_ser = SerdataFromSer,
    .from_ser_iov = SerdataFromSerIov,
    .from_keyhash = SerdataFromKeyhash,
    .from_sample = SerdataFromSample,
    .to_ser = SerdataToSer,
    .to_ser_ref = SerdataToSerRef,
    .to_ser_unref = SerdataToSerUnref,
    .to_sample = SerdataToSample,
    .to_untyped = SerdataToUntyped,
    .untyped_to_sample = UntypedToSample,
    .free = SerdataFree,
    .print = SerdataPrint,
    .get_keyhash = SerdataGetKeyhash,
#ifdef DDS_HAS_SHM
    .get_sample_size = nullptr,  // the bus does not use the shared-memory (iceoryx) transport
    .from_iox_buffer = nullptr,
#endif
};

void SertypeFree(ddsi_sertype* t) {
  ddsi_sertype_fini(t);
  delete reinterpret_cast<RawSertype*>(t);
}

void SertypeZeroSamples(const ddsi_sertype*, void* samples, size_t count) {
  auto* s = static_cast<CycloneSample*>(samples);
  for (size_t i = 0; i < count; ++i) s[i].cdr.clear();
}

void SertypeReallocSamples(void** ptrs, const ddsi_sertype*, void* old, size_t oldcount, size_t count) {
  auto* fresh = new CycloneSample[count];
  auto* prev = static_cast<CycloneSample*>(old);
  for (size_t i = 0; i < std::min(oldcount, count); ++i) fresh[i] = std::move(prev[i]);
  delete[] prev;
  for (size_t i = 0; i < count; ++i) ptrs[i] = &fresh[i];
}

void SertypeFreeSamples(const ddsi_sertype*, void** ptrs, size_t count, dds_free_op_t op) {
  if (count == 0) return;
  auto* s = static_cast<CycloneSample*>(ptrs[0]);
  if (op & DDS_FREE_CONTENTS_BIT)
    for (size_t i = 0; i < count; ++i) static_cast<CycloneSample*>(ptrs[i])->cdr.clear();
  if (op & DDS_FREE_ALL_BIT) delete[] s;
}

bool SertypeEqual(const ddsi_sertype* a, const ddsi_sertype* b) {
  return AsRawType(a)->key_reader == AsRawType(b)->key_reader && AsRawType(a)->codec == AsRawType(b)->codec;
}

uint32_t SertypeHash(const ddsi_sertype*) { return 0x7a1d5e11u; }

const ddsi_sertype_ops kSertypeOps = {
    .version = ddsi_sertype_v0,
    .arg = nullptr,
    .free = SertypeFree,
    .zero_samples = SertypeZeroSamples,
    .realloc_samples = SertypeReallocSamples,
    .free_samples = SertypeFreeSamples,
    .equal = SertypeEqual,
    .hash = SertypeHash,
    .type_id = nullptr,
    .type_map = nullptr,
    .type_info = nullptr,
    .derive_sertype = nullptr,
    .get_serialized_size = nullptr,
    .serialize_into = nullptr,
};

void Check(dds_return_t rc, const std::string& what) {
  if (rc < 0) throw BusError("Cyclone DDS: " + what + ": " + dds_strretcode(rc));
}

dds_qos_t* MakeQos(const TopicSpec& spec) {
  const QosSettings s = SettingsOf(spec.qos);
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, s.reliable ? DDS_RELIABILITY_RELIABLE : DDS_RELIABILITY_BEST_EFFORT,
                       DDS_MSECS(s.max_blocking_ms));
  dds_qset_history(q, s.keep_all ? DDS_HISTORY_KEEP_ALL : DDS_HISTORY_KEEP_LAST, s.depth);
  dds_qset_durability(q, s.transient_local ? DDS_DURABILITY_TRANSIENT_LOCAL : DDS_DURABILITY_VOLATILE);
  // Late joiners get history from durability_service, not from history.depth.
  dds_qset_durability_service(q, 0, s.keep_all ? DDS_HISTORY_KEEP_ALL : DDS_HISTORY_KEEP_LAST, s.depth,
                              DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED);
  const dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
  dds_qset_data_representation(q, 1, &xcdr1);
  return q;
}

struct QosDeleter {
  void operator()(dds_qos_t* q) const { dds_delete_qos(q); }
};
using QosPtr = std::unique_ptr<dds_qos_t, QosDeleter>;

// A process creates each domain once, with its configuration, and shares it.
class DomainRegistry {
 public:
  static DomainRegistry& Get() {
    static DomainRegistry registry;
    return registry;
  }
  void Acquire(dds_domainid_t id, const std::string& xml) {
    std::lock_guard lock(mutex_);
    auto& entry = domains_[id];
    if (entry.refs++ == 0) {
      entry.handle = dds_create_domain(id, xml.c_str());
      if (entry.handle < 0) {
        const dds_return_t rc = entry.handle;
        domains_.erase(id);
        Check(rc, "cannot create domain " + std::to_string(id) + " (bad XML configuration?)");
      }
    }
  }
  void Release(dds_domainid_t id) {
    std::lock_guard lock(mutex_);
    auto it = domains_.find(id);
    if (it != domains_.end() && --it->second.refs == 0) {
      dds_delete(it->second.handle);
      domains_.erase(it);
    }
  }

 private:
  struct Entry {
    dds_entity_t handle = 0;
    int refs = 0;
  };
  std::mutex mutex_;
  std::map<dds_domainid_t, Entry> domains_;
};

class CycloneWriter final : public RawWriter {
 public:
  CycloneWriter(dds_entity_t writer, const ddsi_sertype* type) : writer_(writer), type_(type) {}
  ~CycloneWriter() override { dds_delete(writer_); }

  void Write(std::span<const uint8_t> cdr) override { Write(NewSerdataFrom(type_, SDK_DATA, cdr)); }

  void WriteOwned(std::vector<uint8_t>&& cdr) override {
    auto* d = new RawSerdata();
    ddsi_serdata_init(&d->base, type_, SDK_DATA);
    d->size = static_cast<uint32_t>(cdr.size());
    d->bytes = std::move(cdr);
    Pad(d);
    Write(d);
  }

  std::vector<uint8_t> AcquireBuffer() override {
    return const_cast<RawSertype*>(AsRawType(type_))->pool.Acquire();
  }

  int MatchedReaders() const override {
    dds_publication_matched_status_t st{};
    Check(dds_get_publication_matched_status(writer_, &st), "matched status");
    return static_cast<int>(st.current_count);
  }

  bool WaitForAcknowledgments(std::chrono::milliseconds timeout) override {
    return dds_wait_for_acks(writer_, DDS_MSECS(timeout.count())) == DDS_RETCODE_OK;
  }

 private:
  void Write(RawSerdata* d) {
    try {
      ComputeKeyHash(d, AsRawType(type_));
    } catch (const CdrError& e) {
      delete d;
      throw BusError(std::string("cannot publish a malformed message: ") + e.what());
    }
    Check(dds_writecdr(writer_, &d->base), "write");  // takes ownership of d
  }

  const dds_entity_t writer_;
  const ddsi_sertype* const type_;
};

class CycloneReader final : public RawReader {
 public:
  explicit CycloneReader(bool wants_decoded) : wants_decoded_(wants_decoded) {}
  ~CycloneReader() override {
    if (reader_ > 0) dds_delete(reader_);
  }

  void Attach(dds_entity_t reader) { reader_ = reader; }

  static void OnDataAvailable(dds_entity_t, void* arg) { static_cast<CycloneReader*>(arg)->Signal(); }

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
    constexpr uint32_t kBatch = 64;
    ddsi_serdata* batch[kBatch];
    dds_sample_info_t infos[kBatch];
    std::size_t taken = 0;
    while (taken < max) {
      const uint32_t want = static_cast<uint32_t>(std::min<std::size_t>(kBatch, max - taken));
      const int n = dds_takecdr(reader_, batch, want, infos, DDS_ANY_STATE);
      if (n <= 0) break;
      for (int i = 0; i < n; ++i) {
        if (infos[i].valid_data) {
          RawSerdata* r = AsRaw(batch[i]);
          RawSample sample;
          // Our reference is the last one (no other reader of this process holds the sample):
          // hand its message or bytes over instead of copying them. Nobody can take a new
          // reference now.
          const bool last = ddsrt_atomic_ld32(&batch[i]->refc) == 1;
          if (r->message && wants_decoded_) {
            sample.message = last ? std::move(r->message) : r->message.Copy();
          } else if (r->message) {
            const std::vector<uint8_t>& bytes = EncodedBytes(batch[i]);
            sample.cdr.assign(bytes.begin(), bytes.begin() + r->size);
          } else if (last) {
            sample.cdr = std::move(r->bytes);
            sample.cdr.resize(r->size);
          } else {
            sample.cdr.assign(r->bytes.begin(), r->bytes.begin() + r->size);
          }
          sample.source_timestamp_ns = infos[i].source_timestamp;
          out.push_back(std::move(sample));
          ++taken;
        }
        ddsi_serdata_unref(batch[i]);
      }
      if (static_cast<uint32_t>(n) < want) return taken;
    }
    if (taken == max) Signal();  // there may be more
    return taken;
  }

  int MatchedWriters() const override {
    dds_subscription_matched_status_t st{};
    Check(dds_get_subscription_matched_status(reader_, &st), "matched status");
    return static_cast<int>(st.current_count);
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

  const bool wants_decoded_;
  dds_entity_t reader_ = 0;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool pending_ = false;
  bool interrupted_ = false;
};

class CycloneParticipant final : public Participant {
 public:
  explicit CycloneParticipant(const BusConfig& config) : Participant(config) {
    std::string xml = kCycloneLoopbackXml;
    if (!config.cyclone_xml.empty()) xml = "file://" + config.cyclone_xml;
    DomainRegistry::Get().Acquire(config.domain_id, xml);
    participant_ = dds_create_participant(config.domain_id, nullptr, nullptr);
    if (participant_ < 0) {
      DomainRegistry::Get().Release(config.domain_id);
      Check(participant_, "cannot create participant on domain " + std::to_string(config.domain_id));
    }
  }

  ~CycloneParticipant() override {
    dds_delete(participant_);
    DomainRegistry::Get().Release(config().domain_id);
  }

  std::unique_ptr<RawWriter> CreateRawWriter(const TopicSpec& spec) override {
    const auto [topic, type] = GetTopic(spec);
    QosPtr qos(MakeQos(spec));
    const char* partition = spec.partition.c_str();
    dds_qset_partition(qos.get(), 1, &partition);
    const dds_entity_t publisher = dds_create_publisher(participant_, qos.get(), nullptr);
    Check(publisher, "create publisher for " + spec.topic);
    const dds_entity_t writer = dds_create_writer(publisher, topic, qos.get(), nullptr);
    Check(writer, "create writer for " + spec.topic);
    return std::make_unique<CycloneWriter>(writer, type);
  }

  std::unique_ptr<RawReader> CreateRawReader(const TopicSpec& spec) override {
    const auto [topic, type] = GetTopic(spec);
    QosPtr qos(MakeQos(spec));
    const char* partition = spec.partition.c_str();
    dds_qset_partition(qos.get(), 1, &partition);
    const dds_entity_t subscriber = dds_create_subscriber(participant_, qos.get(), nullptr);
    Check(subscriber, "create subscriber for " + spec.topic);
    auto reader = std::make_unique<CycloneReader>(spec.codec != nullptr);
    dds_listener_t* listener = dds_create_listener(reader.get());
    dds_lset_data_available(listener, &CycloneReader::OnDataAvailable);
    const dds_entity_t handle = dds_create_reader(subscriber, topic, qos.get(), listener);
    dds_delete_listener(listener);
    Check(handle, "create reader for " + spec.topic);
    reader->Attach(handle);
    return reader;
  }

 private:
  std::pair<dds_entity_t, const ddsi_sertype*> GetTopic(const TopicSpec& spec) {
    std::lock_guard lock(mutex_);
    auto it = topics_.find(spec.topic);
    if (it != topics_.end()) {
      if (it->second.type_name != spec.type_name)
        throw BusError("topic " + spec.topic + " already has type " + it->second.type_name);
      return {it->second.topic, it->second.sertype};
    }
    auto* st = new RawSertype();
    st->key_reader = spec.key_reader;
    st->codec = spec.codec;
    ddsi_sertype_init_flags(&st->base, spec.type_name.c_str(), &kSertypeOps, &kSerdataOps,
                            spec.key_reader == nullptr ? DDSI_SERTYPE_FLAG_TOPICKIND_NO_KEY : 0u);
    st->base.allowed_data_representation = DDS_DATA_REPRESENTATION_FLAG_XCDR1;
    ddsi_sertype* actual = &st->base;
    const dds_entity_t topic = dds_create_topic_sertype(participant_, spec.topic.c_str(), &actual, nullptr,
                                                        nullptr, nullptr);
    Check(topic, "create topic " + spec.topic);
    topics_[spec.topic] = {topic, actual, spec.type_name};
    return {topic, actual};
  }

  struct TopicEntry {
    dds_entity_t topic;
    const ddsi_sertype* sertype;
    std::string type_name;
  };
  dds_entity_t participant_ = 0;
  std::mutex mutex_;
  std::map<std::string, TopicEntry> topics_;
};

}  // namespace

std::unique_ptr<Participant> CreateCycloneParticipant(const BusConfig& config) {
  return std::make_unique<CycloneParticipant>(config);
}

}  // namespace rslam::bus
