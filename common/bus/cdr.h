#pragma once
// XCDR1 (plain CDR) encoding of the project's message types: little-endian, with the 4-byte
// encapsulation header 00 01 00 00 (CDR_LE), primitives aligned to their size relative to the
// end of that header, strings as uint32 length (including the NUL) + bytes + NUL, sequences as
// uint32 count + elements, enums as int32. This is what Cyclone DDS and Fast DDS put on the wire
// for @final types, so both vendors carry the same bytes and the recorder stores them unchanged.
//
// The generated message code (build/generated/rslam/msg/*.h, from idl/) calls these.

#include <algorithm>
#include <bit>
#include <cstdio>
#include <cstdint>
#include <cstring>
#include <span>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace rslam::bus {

static_assert(std::endian::native == std::endian::little, "rslam assumes a little-endian host");

// A malformed serialized message: truncated, a length beyond the buffer, an unknown enum value.
class CdrError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

inline constexpr uint8_t kEncapsulationCdrLe[4] = {0x00, 0x01, 0x00, 0x00};
inline constexpr uint8_t kEncapsulationCdrBe[4] = {0x00, 0x00, 0x00, 0x00};

class CdrWriter {
 public:
  // Appends to out, starting with the encapsulation header.
  explicit CdrWriter(std::vector<uint8_t>& out) : out_(out), base_(out.size() + 4) {
    out_.insert(out_.end(), std::begin(kEncapsulationCdrLe), std::end(kEncapsulationCdrLe));
  }

  template <class T>
    requires std::is_arithmetic_v<T>
  void Write(T v) {
    Align(sizeof(T));
    const auto* p = reinterpret_cast<const uint8_t*>(&v);
    out_.insert(out_.end(), p, p + sizeof(T));
  }
  void Write(bool v) { out_.push_back(v ? 1 : 0); }
  void Write(const std::string& s) {
    Write<uint32_t>(static_cast<uint32_t>(s.size() + 1));
    out_.insert(out_.end(), s.begin(), s.end());
    out_.push_back(0);
  }
  template <class E>
    requires std::is_enum_v<E>
  void Write(E e) {
    Write<int32_t>(static_cast<int32_t>(e));
  }
  // Sequences of primitives are copied in one go.
  template <class T>
    requires std::is_arithmetic_v<T> && (!std::is_same_v<T, bool>)
  void WritePrimitiveSequence(const std::vector<T>& v) {
    Write<uint32_t>(static_cast<uint32_t>(v.size()));
    if (v.empty()) return;
    Align(sizeof(T));
    const auto* p = reinterpret_cast<const uint8_t*>(v.data());
    out_.insert(out_.end(), p, p + v.size() * sizeof(T));
  }
  void Reserve(std::size_t bytes) { out_.reserve(out_.size() + bytes); }

  // Pads the message to a multiple of 4 bytes and records the padding in the last two bits of
  // the encapsulation options (XTypes 7.6.3.1.2), so the bytes a writer sends, a reader takes
  // and a recorder stores are the same.
  void Finish() {
    const std::size_t pad = (4 - (out_.size() - base_) % 4) % 4;
    out_.insert(out_.end(), pad, 0);
    out_[base_ - 1] = static_cast<uint8_t>(pad);
  }

 private:
  void Align(std::size_t n) {
    const std::size_t pos = out_.size() - base_;
    const std::size_t pad = (n - pos % n) % n;
    out_.insert(out_.end(), pad, 0);
  }
  std::vector<uint8_t>& out_;
  const std::size_t base_;
};

class CdrReader {
 public:
  // Reads a buffer that starts with the encapsulation header. Throws CdrError unless it is
  // little- or big-endian plain CDR.
  explicit CdrReader(std::span<const uint8_t> data) : single_(data), segments_(&single_, 1) { Start(); }

  // Reads a message that arrived in pieces (network fragments, in order, back to back) without
  // joining them first: a large sequence of bytes is copied once, from the pieces into the
  // message. The pieces must outlive the reader.
  explicit CdrReader(std::span<const std::span<const uint8_t>> segments) : segments_(segments) { Start(); }

  CdrReader(const CdrReader&) = delete;
  CdrReader& operator=(const CdrReader&) = delete;

  template <class T>
    requires std::is_arithmetic_v<T>
  void Read(T& v) {
    Align(sizeof(T));
    Need(sizeof(T));
    if (pos_ + sizeof(T) <= seg_end_) {  // the usual case: within the current piece
      std::memcpy(&v, At(), sizeof(T));
      pos_ += sizeof(T);
    } else {
      CopyOut(&v, sizeof(T));
    }
    if (swap_) v = ByteSwap(v);
  }
  void Read(bool& v) {
    Need(1);
    uint8_t b = 0;
    CopyOut(&b, 1);
    if (b > 1) throw CdrError("boolean byte " + std::to_string(b) + " at offset " + std::to_string(pos_ - 1));
    v = b == 1;
  }
  void Read(std::string& s) {
    uint32_t n = 0;
    Read(n);
    if (n == 0) throw CdrError("string length 0 (must include the terminating NUL)");
    Need(n);
    if (Contiguous(n)) {
      const auto* p = reinterpret_cast<const char*>(At());
      if (p[n - 1] != 0) throw CdrError("string not NUL-terminated");
      s.assign(p, n - 1);
      pos_ += n;
      return;
    }
    s.resize(n);
    CopyOut(s.data(), n);
    if (s.back() != 0) throw CdrError("string not NUL-terminated");
    s.pop_back();
  }
  template <class E>
    requires std::is_enum_v<E>
  void ReadEnum(E& e, int32_t count) {
    int32_t v = 0;
    Read(v);
    if (v < 0 || v >= count) throw CdrError("enum value " + std::to_string(v) + " out of range");
    e = static_cast<E>(v);
  }
  template <class T>
    requires std::is_arithmetic_v<T> && (!std::is_same_v<T, bool>)
  void ReadPrimitiveSequence(std::vector<T>& v) {
    const uint32_t n = ReadCount(sizeof(T));
    if (n == 0) {
      v.clear();
      return;
    }
    Align(sizeof(T));
    const std::size_t bytes = std::size_t{n} * sizeof(T);
    Need(bytes);
    if constexpr (sizeof(T) == 1) {
      // Bytes (images) in one pass, without zero-filling first (a vector that already holds
      // enough keeps its buffer).
      v.clear();
      v.reserve(n);
      while (v.size() < n) {
        Seek();
        const std::size_t chunk = std::min(std::size_t{n} - v.size(), seg_end_ - pos_);
        const auto* p = reinterpret_cast<const T*>(At());
        v.insert(v.end(), p, p + chunk);
        pos_ += chunk;
      }
    } else {
      v.resize(n);
      CopyOut(v.data(), bytes);
    }
    if (swap_)
      for (auto& x : v) x = ByteSwap(x);
  }
  // A sequence count, checked against the bytes left (each element takes at least
  // min_element_size bytes), so a corrupt count cannot trigger a huge allocation.
  uint32_t ReadCount(std::size_t min_element_size) {
    uint32_t n = 0;
    Read(n);
    if (min_element_size > 0 && std::size_t{n} > remaining() / min_element_size)
      throw CdrError("sequence of " + std::to_string(n) + " elements exceeds the message size");
    return n;
  }
  std::size_t remaining() const { return pos_ <= size_ ? size_ - pos_ : 0; }

 private:
  void Start() {
    for (const auto& segment : segments_) size_ += segment.size();
    seg_end_ = segments_.empty() ? 0 : segments_[0].size();
    uint8_t header[4] = {};
    if (size_ < 4) throw CdrError("not plain CDR (encapsulation header missing)");
    CopyOut(header, 4);
    if (header[0] != 0x00 || (header[1] != 0x00 && header[1] != 0x01)) {
      char text[48];
      std::snprintf(text, sizeof(text), "not plain CDR (encapsulation header %02x %02x)", header[0], header[1]);
      throw CdrError(text);
    }
    swap_ = header[1] == 0x00;
  }
  template <class T>
  static T ByteSwap(T v) {
    uint8_t b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    std::memcpy(&v, b, sizeof(T));
    return v;
  }
  void Align(std::size_t n) {
    const std::size_t rel = pos_ - 4;
    pos_ += (n - rel % n) % n;
  }
  void Need(std::size_t n) const {
    if (pos_ > size_ || size_ - pos_ < n)
      throw CdrError("truncated: need " + std::to_string(n) + " bytes at offset " + std::to_string(pos_) + " of " +
                     std::to_string(size_));
  }
  // Moves to the segment holding pos_ (positions only grow). Callers checked pos_ < size_.
  void Seek() {
    while (pos_ >= seg_end_ && segment_ + 1 < segments_.size()) {
      seg_begin_ = seg_end_;
      seg_end_ += segments_[++segment_].size();
    }
  }
  bool Contiguous(std::size_t n) {
    Seek();
    return pos_ + n <= seg_end_;
  }
  const uint8_t* At() const { return segments_[segment_].data() + (pos_ - seg_begin_); }
  // Copies n bytes (checked with Need) from pos_ on, across segments if need be.
  void CopyOut(void* out, std::size_t n) {
    auto* dst = static_cast<uint8_t*>(out);
    while (n > 0) {
      Seek();
      const std::size_t chunk = std::min(n, seg_end_ - pos_);
      std::memcpy(dst, At(), chunk);
      dst += chunk;
      pos_ += chunk;
      n -= chunk;
    }
  }
  const std::span<const uint8_t> single_;
  const std::span<const std::span<const uint8_t>> segments_;
  std::size_t size_ = 0;       // all segments
  std::size_t segment_ = 0;    // the segment holding pos_ (after Seek)
  std::size_t seg_begin_ = 0;  // its first byte's offset in the message
  std::size_t seg_end_ = 0;    // one past its last byte
  std::size_t pos_ = 0;
  bool swap_ = false;
};

// The key fields of a message in big-endian CDR, as DDS hashes them (MD5 of these bytes is the
// instance key hash on both vendors).
class CdrKeyWriter {
 public:
  void Write(const std::string& s) {
    WriteU32(static_cast<uint32_t>(s.size() + 1));
    bytes_.insert(bytes_.end(), s.begin(), s.end());
    bytes_.push_back(0);
  }
  template <class T>
    requires std::is_integral_v<T>
  void Write(T v) {
    while (bytes_.size() % sizeof(T)) bytes_.push_back(0);
    for (int i = sizeof(T) - 1; i >= 0; --i) bytes_.push_back(static_cast<uint8_t>(uint64_t(v) >> (8 * i)));
  }
  const std::vector<uint8_t>& bytes() const { return bytes_; }
  void Clear() { bytes_.clear(); }

 private:
  void WriteU32(uint32_t v) { Write<uint32_t>(v); }
  std::vector<uint8_t> bytes_;
};

}  // namespace rslam::bus
