// canhil/laptop/hwcomm.hpp — the reference low-level communication handler:
// an FTT slave between the CAN bus and this robot's RTDB.
//
//   bus -> RTDB   M4_1 + M4_2 -> CMD_POS    M2, M9 -> CMD_INFO   M9 -> CMD_GRABBER_INFO
//                 M8 -> CMD_IMU             M10 (+ own counts) -> CMD_HWERRORS
//   RTDB -> bus   CMD_VEL -> M6_1 + M6_2 in their synchronous slots
//                 CMD_KICKER (power != 0) -> M7 once, then power reset to 0; CMD_GRABBER changes -> M7
//                 CMD_SETPOSE (pending) -> M5_1 + M5_2 once
//
// Uses only the DBC codec and the RTDB C API (DB_init by the caller); the
// transport and the clock are the caller's: canhil-hwcomm uses SocketCAN and
// the wall clock, tests the memory bus and virtual time.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "canhil/frames/ftt_slot.hpp"
#include "canhil/frames/messages.hpp"

namespace canhil::laptop {

inline constexpr std::size_t kMaxLatencySamples = 1'000'000;

struct HwCommStats {
  /// Per message of the set, in the codec's order (MessageSet::codec().messages()):
  /// counted by index, so a received frame costs no allocation.
  std::vector<std::uint64_t> received;
  std::vector<std::uint64_t> sent;
  std::uint64_t wrong_length = 0;
  std::uint64_t out_of_range = 0;
  std::uint64_t unknown_id = 0;
  std::uint64_t missed_tms = 0;  ///< gaps in the TM's ec_counter
  std::uint64_t send_failed = 0;
  std::uint64_t kicks_sent = 0;
  std::vector<Nanos> latencies;  ///< receive timestamp -> RTDB write, per update (first kMaxLatencySamples)
};

class HwComm {
 public:
  using Send = std::function<bool(const frames::CanFrame&)>;
  using Clock = std::function<Nanos()>;

  /// `ec` is the elementary cycle (the TM carries the window, not the EC).
  /// `agent` < 0: this process's agent (DB_init); else that agent's database
  /// through DB_init_all (a process serving several robots, e.g. canhil run).
  HwComm(std::shared_ptr<const frames::MessageSet> set, Nanos ec, Send send, Clock clock, int agent = -1);

  /// A received frame with its receive timestamp.
  void on_frame(const frames::CanFrame& frame, Nanos rx_time);
  /// When the handler must act next (its M6 slot), or kNever.
  Nanos next_deadline() const noexcept { return m6_at_; }
  /// Acts at `now` (call at or after next_deadline()).
  void on_time(Nanos now);

  const HwCommStats& stats() const noexcept { return stats_; }
  /// Frames of message `name` received and sent so far (0 for a name the set does not have).
  std::uint64_t received(std::string_view name) const noexcept;
  std::uint64_t sent(std::string_view name) const noexcept;
  /// Multi-line summary for the end of a run.
  std::string summary() const;

 private:
  void send(const frames::CanFrame& f, const frames::MessageCodec& message);
  std::size_t index_of(const frames::MessageCodec& m) const noexcept;
  void on_tm(const frames::Tm& tm, Nanos rx_time);
  void latency(Nanos rx_time);
  void write_hwerrors();
  int get(int id, void* value) const;
  void put(int id, void* value) const;

  std::shared_ptr<const frames::MessageSet> set_;
  Nanos ec_;
  Send send_;
  Clock clock_;
  HwCommStats stats_;
  frames::SyncSlot m6_slot_;
  Nanos m6_at_ = kNever;  // the M6 slot to serve (the last TM's may be replaced by the next)
  bool have_tm_ = false;
  std::uint16_t last_ec_ = 0;
  bool have_m4_1_ = false;
  frames::M4_1 m4_1_{};
  bool have_pose_ = false;
  float last_px_ = 0, last_py_ = 0, last_pa_ = 0;
  Nanos last_m7_ = kLongAgo;
  Nanos last_m5_ = kLongAgo;
  int last_grabber_ = -1;
  std::uint8_t m6_seq_ = 0;
  frames::M10 m10_{};
  int agent_ = -1;
};

}  // namespace canhil::laptop
