#include "canhil/frames/wire.hpp"

#include <algorithm>
#include <bit>
#include <cstring>

namespace canhil::frames {
namespace {

// CRC delimiter, ACK slot, ACK delimiter, end of frame, intermission: never stuffed.
constexpr std::uint32_t kTailBits = 1 + 1 + 1 + 7 + 3;

// A CRC register, fed one bit at a time (first bit first).
class Crc {
 public:
  constexpr Crc(std::uint32_t polynomial, int width, std::uint32_t initial)
      : poly_(polynomial),
        top_(std::uint32_t{1} << (width - 1)),
        mask_((std::uint32_t{1} << width) - 1),
        reg_(initial) {}
  constexpr void feed(bool bit) noexcept {
    const bool flip = ((reg_ & top_) != 0) != bit;
    reg_ = (reg_ << 1) & mask_;
    if (flip) reg_ ^= poly_;
  }
  constexpr std::uint32_t value() const noexcept { return reg_; }

 private:
  std::uint32_t poly_, top_, mask_, reg_;
};

// The frame's bits in order, handed to `sink(const WireBit&)`; the sink
// returns false to stop early. One encoder for counting, for locating a bit
// and for the tests' bounds.
template <class Sink>
class Encoder {
 public:
  Encoder(const WireFrame& f, Sink& sink) : f_(f), sink_(sink) {}

  void run() {
    // The arbitration and control fields.
    put(false, kProtocolLocationSof);
    const std::uint32_t base = f_.extended ? (f_.id >> 18) & 0x7FFu : f_.id & kStandardIdMask;
    put_field(base >> 3, 8, kProtocolLocationId28To21);
    put_field(base & 0x7u, 3, kProtocolLocationId20To18);
    const bool rtr = f_.remote && !f_.fd;
    if (f_.extended) {
      put(true, kProtocolLocationSrtr);  // SRR
      put(true, kProtocolLocationIde);
      put_field((f_.id >> 13) & 0x1Fu, 5, kProtocolLocationId17To13);
      put_field((f_.id >> 5) & 0xFFu, 8, kProtocolLocationId12To05);
      put_field(f_.id & 0x1Fu, 5, kProtocolLocationId04To00);
      put(rtr, kProtocolLocationRtr);  // RTR, or FD's RRS (dominant)
      if (f_.fd) {
        put(true, kProtocolLocationRes1);  // FDF
        put(false, kProtocolLocationRes0);
      } else {
        put(false, kProtocolLocationRes1);
        put(false, kProtocolLocationRes0);
      }
    } else {
      put(rtr, kProtocolLocationRtr);  // RTR, or FD's RRS
      put(false, kProtocolLocationIde);
      if (f_.fd) {
        put(true, kProtocolLocationRes1);  // FDF
        put(false, kProtocolLocationRes0);
      } else {
        put(false, kProtocolLocationRes0);  // r0
      }
    }
    if (f_.fd) {
      put(f_.brs, kProtocolLocationUnspecified);
      fast_ = f_.brs;  // from here to the CRC delimiter, at the data bit rate
      put(f_.esi, kProtocolLocationUnspecified);
    }
    const std::uint8_t len = f_.fd ? fd_length(fd_dlc(f_.len)) : std::min<std::uint8_t>(f_.len, 8);
    const std::uint32_t dlc = f_.fd ? fd_dlc(f_.len) : (f_.len8_dlc > 8 ? f_.len8_dlc : len);
    put_field(dlc, 4, kProtocolLocationDlc);
    if (!rtr) {
      for (std::uint8_t i = 0; i < len; ++i) put_field(f_.data[i], 8, kProtocolLocationData);
    }
    if (!f_.fd) {
      put_field(crc15_.value(), 15, kProtocolLocationCrc);
      flush_stuff();
    } else {
      fd_crc_field(len);
    }
    fast_ = false;
    emit(true, kProtocolLocationCrcDelimiter, false);
    emit(true, kProtocolLocationAck, false);  // sent recessive; a receiver's acknowledgement makes it dominant
    emit(true, kProtocolLocationAckDelimiter, false);
    for (int i = 0; i < 7; ++i) emit(true, kProtocolLocationEof, false);
    for (int i = 0; i < 3; ++i) emit(true, kProtocolLocationIntermission, false);
  }

 private:
  // A bit of the dynamically stuffed part.
  void put(bool recessive, std::uint8_t location) {
    flush_stuff();
    if (!f_.fd && !in_crc_) crc15_.feed(recessive);
    emit(recessive, location, false);
    count_run(recessive);
  }
  void put_field(std::uint32_t value, int count, std::uint8_t location) {
    if (location == kProtocolLocationCrc) in_crc_ = true;
    for (int i = count - 1; i >= 0; --i) put(((value >> i) & 1u) != 0, location);
  }
  void count_run(bool level) {
    if (level == last_ && run_ > 0) {
      ++run_;
    } else {
      last_ = level;
      run_ = 1;
    }
    if (run_ == 5) stuff_due_ = true;
  }
  // After five equal bits, one of the other value; it starts the next run.
  void flush_stuff() {
    if (!stuff_due_) return;
    stuff_due_ = false;
    ++dynamic_stuff_;
    const bool level = !last_;
    emit(level, location_, true);
    last_ = level;
    run_ = 1;
  }
  // FD: a fixed stuff bit, the stuff count and the CRC, a fixed stuff bit before every fourth bit.
  void fd_crc_field(std::uint8_t len) {
    stuff_due_ = false;  // the first fixed stuff bit stands in for a dynamic one due here
    in_fd_tail_ = true;  // the CRC covers the stuff count, not the fixed stuff bits
    Crc& fd_crc = len <= 16 ? fd_crc17_ : fd_crc21_;
    static constexpr std::uint8_t kGray[8] = {0, 1, 3, 2, 6, 7, 5, 4};
    const std::uint32_t gray = kGray[dynamic_stuff_ % 8];
    const std::uint32_t parity = (gray ^ (gray >> 1) ^ (gray >> 2)) & 1u;
    const std::uint32_t count = (gray << 1) | parity;
    for (int i = 3; i >= 0; --i) fd_crc.feed(((count >> i) & 1u) != 0);
    const int width = len <= 16 ? 17 : 21;
    const std::uint32_t crc = fd_crc.value();
    const int total = 4 + width;
    for (int i = 0; i < total; ++i) {
      if (i % 4 == 0) emit(!last_emitted_, kProtocolLocationCrc, true);
      const bool bit = i < 4 ? ((count >> (3 - i)) & 1u) != 0 : ((crc >> (width - 1 - (i - 4))) & 1u) != 0;
      emit(bit, kProtocolLocationCrc, false);
    }
  }
  void emit(bool recessive, std::uint8_t location, bool stuff) {
    if (stopped_) return;
    location_ = location;
    last_emitted_ = recessive;
    if (f_.fd && !in_fd_tail_) {
      fd_crc17_.feed(recessive);
      fd_crc21_.feed(recessive);
    }
    if (!sink_(WireBit{recessive, location, fast_, stuff})) stopped_ = true;
  }

  const WireFrame& f_;
  Sink& sink_;
  Crc crc15_{0x4599, 15, 0};
  // FD's CRCs over the stuffed stream from SOF to the data's end and the
  // stuff count; the frame's length picks one.
  Crc fd_crc17_{0x1685B, 17, 1u << 16};   // x^17 + x^16 + x^14 + x^13 + x^11 + x^6 + x^4 + x^3 + x + 1
  Crc fd_crc21_{0x102899, 21, 1u << 20};  // x^21 + x^20 + x^13 + x^11 + x^7 + x^4 + x^3 + 1
  bool in_crc_ = false;
  bool in_fd_tail_ = false;
  bool fast_ = false;
  bool last_ = false;
  bool last_emitted_ = true;
  int run_ = 0;
  bool stuff_due_ = false;
  std::uint32_t dynamic_stuff_ = 0;
  std::uint8_t location_ = kProtocolLocationSof;
  bool stopped_ = false;
};

}  // namespace

WireFrame wire_frame(const CanFrame& frame) noexcept {
  WireFrame w;
  w.id = frame.id;
  w.extended = frame.extended;
  w.remote = frame.kind == FrameKind::kRemote;
  w.len = std::min<std::uint8_t>(frame.len, kMaxDataBytes);
  w.len8_dlc = frame.len8_dlc;
  std::copy(frame.data.begin(), frame.data.end(), w.data.begin());
  return w;
}

std::uint8_t fd_dlc(std::uint8_t len) noexcept {
  if (len <= 8) return len;
  if (len <= 24) return static_cast<std::uint8_t>(9 + (len - 9) / 4);  // 12, 16, 20, 24
  if (len <= 32) return 13;
  if (len <= 48) return 14;
  return 15;
}

std::uint8_t fd_length(std::uint8_t dlc) noexcept {
  static constexpr std::uint8_t kLengths[16] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64};
  return kLengths[dlc & 0xFu];
}

std::uint16_t can_crc15(const std::uint8_t* bits, std::uint32_t count) noexcept {
  Crc crc(0x4599, 15, 0);
  for (std::uint32_t i = 0; i < count; ++i) crc.feed(bits[i] != 0);
  return static_cast<std::uint16_t>(crc.value());
}

std::uint32_t can_fd_crc(const std::uint8_t* bits, std::uint32_t count, int width, bool iso) noexcept {
  Crc crc(width == 17 ? 0x1685Bu : 0x102899u, width, iso ? std::uint32_t{1} << (width - 1) : 0);
  for (std::uint32_t i = 0; i < count; ++i) crc.feed(bits[i] != 0);
  return crc.value();
}

namespace {

// The stuffed part of a classic frame (at most 39 + 64 + 15 bits, and up to
// 7 of padding) as one number, its last bit lowest.
__extension__ using Stream = unsigned __int128;  // NOLINT: GCC's and Clang's 128-bit integer

// CRC-15 by the message's nibbles, each looked up on its own: the CRC is
// linear, so it is the xor of each nibble's CRC with the zeros after it
// (bits 4k..4k+3 from the message's end: a nibble followed by 4k zero bits),
// and zeros before a message leave it unchanged. The lookups do not wait for
// one another, as a register stepped by table would (a run's frames come
// between physics steps, so each lookup may be a cache miss).
constexpr std::size_t kCrcNibbles = 26;  // 104 bits: an extended frame's 39 + 64
struct Crc15ByNibble {
  std::array<std::array<std::uint16_t, 16>, kCrcNibbles> at{};
  constexpr Crc15ByNibble() {
    for (std::size_t k = 0; k < kCrcNibbles; ++k) {
      for (std::uint32_t nibble = 0; nibble < 16; ++nibble) {
        Crc crc(0x4599, 15, 0);
        for (std::size_t i = 0; i < 4 + 4 * k; ++i) crc.feed(i < 4 && ((nibble >> (3 - i)) & 1u) != 0);
        at[k][nibble] = static_cast<std::uint16_t>(crc.value());
      }
    }
  }
};
constexpr Crc15ByNibble kCrc15;

std::uint32_t crc15_of(Stream message) noexcept {
  const auto low = static_cast<std::uint64_t>(message), high = static_cast<std::uint64_t>(message >> 64);
  std::uint32_t crc = 0;
#pragma GCC unroll 16
  for (std::size_t k = 0; k < 16; ++k) crc ^= kCrc15.at[k][(low >> (4 * k)) & 0xFu];
#pragma GCC unroll 16
  for (std::size_t k = 16; k < kCrcNibbles; ++k) crc ^= kCrc15.at[k][(high >> (4 * (k - 16))) & 0xFu];
  return crc;
}

// Bit stuffing as a machine over the stuffed part's bits: its state is the
// last level and how many equal bits end the stream so far (a stuff bit,
// after the fifth, is one of the other level). Stepping a whole byte by
// table gives the stuff bits it adds and the state after it: the count
// every frame on a timed wire needs. The same count as the encoder's
// (tests/frames/wire_test.cpp checks both against an independent one).
struct StuffTable {
  // A state: 0 before any bit, else 1 + 4 * level + (equal bits - 1). A
  // bit's step packs the stuff bits added (high nibble) and the next state.
  static constexpr std::uint8_t bit(std::uint8_t state, bool level) noexcept {
    const int v = level ? 1 : 0;
    if (state != 0 && (state - 1) / 4 == v) {
      const int equal = (state - 1) % 4 + 2;
      if (equal == 5) return static_cast<std::uint8_t>(0x10 | (1 + 4 * (1 - v)));  // the stuff bit starts a run
      return static_cast<std::uint8_t>(1 + 4 * v + equal - 1);
    }
    return static_cast<std::uint8_t>(1 + 4 * v);
  }
  // A byte's step, indexed by state * 256 + byte: the stuff bits added
  // (top 4 bits) and the next state (one byte: the table fits in fewer lines).
  std::array<std::uint8_t, std::size_t{9} * 256> t{};
  constexpr StuffTable() {
    for (std::uint8_t state = 0; state < 9; ++state) {
      for (std::uint32_t byte = 0; byte < 256; ++byte) {
        std::uint8_t st = state, added = 0;
        for (int k = 7; k >= 0; --k) {
          const std::uint8_t step = bit(st, ((byte >> k) & 1u) != 0);
          added = static_cast<std::uint8_t>(added + (step >> 4));
          st = step & 0xFu;
        }
        t[state * 256u + byte] = static_cast<std::uint8_t>((added << 4) | st);
      }
    }
  }
};
constexpr StuffTable kStuffTable;

// Steps the stuffing machine over `bytes` bytes of `x`, its first at the top.
std::uint32_t stuff_bytes(Stream& x, std::uint32_t bytes, std::uint32_t& state) noexcept {
  std::uint32_t stuffed = 0;
  for (std::uint32_t k = 0; k < bytes; ++k) {
    const std::uint32_t step = kStuffTable.t[(state << 8) | static_cast<std::uint32_t>(x >> 120)];
    stuffed += step >> 4;
    state = step & 0xFu;
    x <<= 8;
  }
  return stuffed;
}

// A classic frame's bits without the encoder: the stuffed part as one
// number, its CRC-15 by nibbles, its stuff bits a byte at a time: the bytes
// before the CRC while the CRC is worked out, then the rest.
FrameBits count_classic(const WireFrame& f) noexcept {
  const bool remote = f.remote;
  const std::uint8_t len = std::min<std::uint8_t>(f.len, 8);
  const std::uint32_t dlc = f.len8_dlc > 8 ? f.len8_dlc : len;
  Stream v = 0;
  std::uint32_t n = 0;
  // From SOF (dominant: a leading 0) to the DLC.
  if (!f.extended) {
    v = (std::uint64_t{f.id & kStandardIdMask} << 7) | (remote ? 0x40u : 0u) | dlc;  // SOF id RTR IDE r0 DLC
    n = 19;
  } else {
    const std::uint64_t base = (f.id >> 18) & 0x7FFu, ext = f.id & 0x3FFFFu;
    v = (base << 27) | (0b11u << 25) | (ext << 7) | (remote ? 0x40u : 0u) | dlc;  // SOF base SRR IDE ext RTR r1 r0 DLC
    n = 39;
  }
  if (!remote && len > 0) {
    std::uint64_t data = 0;  // the first `len` bytes, the first highest
    std::memcpy(&data, f.data.data(), sizeof data);
    if constexpr (std::endian::native == std::endian::little) data = __builtin_bswap64(data);
    data >>= 64 - 8 * len;
    v = (v << (8 * len)) | data;
    n += 8u * len;
  }
  const std::uint32_t crc = crc15_of(v);
  // The stuff bits, a byte at a time from the first bit. Alternating bits
  // ending in a recessive one put before SOF make the count of bits a
  // multiple of 8 and add no stuff bit: none of them runs to five, and
  // the dominant SOF starts a run of its own, as it does from no bit at all.
  const std::uint32_t total = n + 15;
  const std::uint32_t pad = (8 - total % 8) % 8;
  const std::uint32_t top = 128 - (total + pad);  // the padded stream, its first bit at bit 127
  Stream x = ((static_cast<Stream>(0x55u & ((1u << pad) - 1)) << total) | (v << 15)) << top;
  std::uint32_t state = 0;
  const std::uint32_t before_crc = (pad + n) / 8;  // whole bytes before the CRC's first bit
  std::uint32_t stuffed = stuff_bytes(x, before_crc, state);
  x |= static_cast<Stream>(crc) << (top + 8 * before_crc);
  stuffed += stuff_bytes(x, (total + pad) / 8 - before_crc, state);
  return FrameBits{total + stuffed + kTailBits, 0};
}

}  // namespace

FrameBits count_bits(const WireFrame& frame) noexcept {
  if (!frame.fd) return count_classic(frame);
  FrameBits bits;
  auto sink = [&bits](const WireBit& b) {
    ++(b.fast ? bits.fast : bits.nominal);
    return true;
  };
  Encoder<decltype(sink)>(frame, sink).run();
  return bits;
}

FrameBits prefix_bits(const WireFrame& frame, std::uint32_t count) noexcept {
  FrameBits bits;
  auto sink = [&bits, count](const WireBit& b) {
    if (bits.total() == count) return false;
    ++(b.fast ? bits.fast : bits.nominal);
    return true;
  };
  Encoder<decltype(sink)>(frame, sink).run();
  return bits;
}

WireBit bit_at(const WireFrame& frame, std::uint32_t index) noexcept {
  WireBit found{true, kProtocolLocationIntermission, false, false};
  std::uint32_t i = 0;
  auto sink = [&](const WireBit& b) {
    if (i++ != index) return true;
    found = b;
    return false;
  };
  Encoder<decltype(sink)>(frame, sink).run();
  return found;
}

std::uint32_t frame_bits(const CanFrame& f) noexcept {
  if (f.kind == FrameKind::kError) return kErrorFrameBits;
  return count_bits(wire_frame(f)).total();
}

std::uint32_t best_case_frame_bits(std::uint8_t data_bytes, bool extended) noexcept {
  const std::uint32_t region = (extended ? 54u : 34u) + 8u * data_bytes;
  return region + kTailBits;
}

std::uint32_t worst_case_frame_bits(std::uint8_t data_bytes, bool extended) noexcept {
  const std::uint32_t region = (extended ? 54u : 34u) + 8u * data_bytes;
  return region + (region - 1) / 4 + kTailBits;
}

}  // namespace canhil::frames
