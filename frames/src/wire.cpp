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
  wire_frame_into(frame, w);
  return w;
}

void wire_frame_into(const CanFrame& frame, WireFrame& out) noexcept {
  out.id = frame.id;
  out.extended = frame.extended;
  out.remote = frame.kind == FrameKind::kRemote;
  out.fd = false;
  out.brs = false;
  out.esi = false;
  out.len = std::min<std::uint8_t>(frame.len, kMaxDataBytes);
  out.len8_dlc = frame.len8_dlc;
  std::copy(frame.data.begin(), frame.data.end(), out.data.begin());
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

// The stuffed part of a classic frame (at most 39 + 64 + 15 bits) as one
// number, its last bit lowest.
__extension__ using Stream = unsigned __int128;  // NOLINT: GCC's and Clang's 128-bit integer

// CRC-15 by the message's bytes, each looked up on its own: the CRC is
// linear, so it is the xor of each byte's CRC with the zeros after it (bits
// 8k..8k+7 from the message's end: a byte followed by 8k zero bits), and
// zeros before a message leave it unchanged. The lookups do not wait for
// one another, as a register stepped by table would.
constexpr std::size_t kCrcBytes = 13;  // 104 bits: an extended frame's 39 + 64
struct Crc15ByByte {
  std::array<std::array<std::uint16_t, 256>, kCrcBytes> at{};
  constexpr Crc15ByByte() {
    // Each byte's CRC from its bits': one bit followed by zeros, by position.
    std::array<std::uint16_t, 8 * kCrcBytes> bit{};
    for (std::size_t i = 0; i < bit.size(); ++i) {
      Crc crc(0x4599, 15, 0);
      crc.feed(true);
      for (std::size_t z = 0; z < i; ++z) crc.feed(false);
      bit[i] = static_cast<std::uint16_t>(crc.value());
    }
    for (std::size_t k = 0; k < kCrcBytes; ++k) {
      for (std::uint32_t byte = 0; byte < 256; ++byte) {
        std::uint16_t crc = 0;
        for (std::size_t b = 0; b < 8; ++b) {
          if (((byte >> b) & 1u) != 0) crc = static_cast<std::uint16_t>(crc ^ bit[8 * k + b]);
        }
        at[k][byte] = crc;
      }
    }
  }
};
constexpr Crc15ByByte kCrc15;

std::uint32_t crc15_of(Stream message) noexcept {
  const auto low = static_cast<std::uint64_t>(message), high = static_cast<std::uint64_t>(message >> 64);
  std::uint32_t crc = 0;
#pragma GCC unroll 8
  for (std::size_t k = 0; k < 8; ++k) crc ^= kCrc15.at[k][(low >> (8 * k)) & 0xFFu];
#pragma GCC unroll 8
  for (std::size_t k = 8; k < kCrcBytes; ++k) crc ^= kCrc15.at[k][(high >> (8 * (k - 8))) & 0xFFu];
  return crc;
}

// Bit stuffing as a machine over the stuffed part's bits, in eight states:
// the last bit's level and how many equal bits end the stream so far, 1 to
// 4 (a fifth is followed by a stuff bit of the other level, which starts a
// run of its own). A state s is 4 * level + equal - 1; no bit at all acts as
// a lone recessive bit (the dominant SOF starts a run either way).
struct StuffRows {
  // row[byte]: what the byte does from each state s, in its bits 8s..8s+7:
  // the stuff bits it adds (0 to 2, bits 6-7) and the state after it, times
  // eight (bits 0-5): stepping is a shift of the byte's row by the state,
  // whose rows do not wait on one another as rows of a table indexed by
  // state and byte would.
  std::array<std::uint64_t, 256> row{};
  static constexpr std::uint32_t bit(std::uint32_t state, std::uint32_t level, std::uint32_t& added) noexcept {
    if (state / 4 != level) return 4 * level;
    if (state % 4 == 3) {  // the fifth equal bit: a stuff bit of the other level follows
      ++added;
      return 4 * (1 - level);
    }
    return state + 1;
  }
  constexpr StuffRows() {
    for (std::uint32_t byte = 0; byte < 256; ++byte) {
      for (std::uint32_t from = 0; from < 8; ++from) {
        std::uint32_t state = from, added = 0;
        for (int k = 7; k >= 0; --k) state = bit(state, (byte >> k) & 1u, added);
        row[byte] |= std::uint64_t{(added << 6) | (state * 8)} << (8 * from);
      }
    }
  }
};
constexpr StuffRows kStuffRows;
constexpr std::uint32_t kStuffStart = 4 * 8;  // a recessive bit's state, times eight

// A classic frame's bits without the encoder: the stuffed part as one
// number, its CRC-15 by bytes, its stuff bits a byte at a time (the same
// count as the encoder's: tests/frames/wire_test.cpp checks both against an
// independent one).
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
  // The stuffed part as 15 bytes, its first bit at bit 119 (bits 120-127
  // unused): alternating bits ending in a recessive one fill the room before
  // SOF and add no stuff bit (none of them runs to five, and SOF starts a
  // run), so that every frame takes the same 15 steps, none of them a branch.
  const std::uint32_t total = n + 15;
  constexpr std::uint32_t kBytes = 15;
  const Stream fill = (Stream{0x5555555555555555u} << 64) | 0x5555555555555555u;
  const Stream x = ((fill & ((Stream{1} << (8 * kBytes - total)) - 1)) << total) | (v << 15) | crc15_of(v);
  std::uint8_t bytes[16];
  const std::uint64_t halves[2] = {static_cast<std::uint64_t>(x >> 64), static_cast<std::uint64_t>(x)};
  for (std::size_t h = 0; h < 2; ++h) {
    std::uint64_t half = halves[h];
    if constexpr (std::endian::native == std::endian::little) half = __builtin_bswap64(half);
    std::memcpy(bytes + (8 * h), &half, sizeof half);
  }
  std::uint64_t shift = kStuffStart, added = 0;  // added: each step's bits 6-7, summed
#pragma GCC unroll 15
  for (std::uint32_t k = 1; k <= kBytes; ++k) {
    const std::uint64_t step = kStuffRows.row[bytes[k]] >> shift;
    added += step & 0xC0u;
    shift = step & 0x38u;
  }
  const auto stuffed = static_cast<std::uint32_t>(added >> 6);
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
