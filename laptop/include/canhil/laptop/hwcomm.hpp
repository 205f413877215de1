// canhil/laptop/hwcomm.hpp — the reference low-level communication handler:
// an FTT slave between the CAN bus and this robot's RTDB.
//
//   bus -> RTDB   M4_1 + M4_2 -> CMD_POS    M2, M9 -> CMD_INFO   M9 -> CMD_GRABBER_INFO
//                 M8 -> CMD_IMU             M10 (+ own counts) -> CMD_HWERRORS
//   RTDB -> bus   CMD_VEL -> M6_1 + M6_2 in their synchronous slots
//                 CMD_KICKER (power != 0) -> M7 once, then power reset to 0; CMD_GRABBER changes -> M7
//                 CMD_SETPOSE (pending) -> M5_1 + M5_2 once
//
// Uses only the DBC codec and the RTDB through rtdb::Database (canhil's or
// the team's library), every item in the team's layout (rtdb::Layout: its
// structs and units; "canhil" or "cambada" shipped); the transport and the
// clock are the caller's: canhil-hwcomm uses SocketCAN and the wall clock,
// tests the memory bus and virtual time. Also, when the layout has them:
// LAST_CMD_VEL echoes every CMD_VEL sent; CMD_HWERRORS carries M10 and the
// handler's own counts.
#pragma once

#include <algorithm>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "canhil/frames/ftt_slot.hpp"
#include "canhil/frames/messages.hpp"
#include "canhil/rtdb/database.hpp"
#include "canhil/rtdb/layout.hpp"

namespace canhil::laptop {

inline constexpr std::size_t kMaxLatencySamples = 1'000'000;

/// The handler's controller as its error frames say (Linux's can_state).
using frames::ControllerState;

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
  // The bus as its controller reports it in error frames (linux/can/error.h),
  // which the handler asks for (CAN_RAW_ERR_FILTER):
  std::uint64_t error_frames = 0;                              ///< every one received
  std::uint64_t bus_errors = 0;                                ///< protocol errors and missing acknowledgements
  std::uint64_t bus_offs = 0;                                  ///< CAN_ERR_BUSOFF
  std::uint64_t restarts = 0;                                  ///< CAN_ERR_RESTARTED
  ControllerState controller = ControllerState::kErrorActive;  ///< as last reported
  std::uint8_t tec = 0;                                        ///< the counters last reported (CAN_ERR_CNT)
  std::uint8_t rec = 0;
  std::vector<Nanos> latencies;  ///< receive timestamp -> RTDB write, per update (first kMaxLatencySamples)
};

class HwComm {
 public:
  using Send = std::function<bool(const frames::CanFrame&)>;
  using Clock = std::function<Nanos()>;

  /// `ec` is the elementary cycle (the TM carries the window, not the EC).
  /// The handler serves agent `space`'s database in `db` (canhil's RTDB or the
  /// team's library; a process serving one robot: db.spaces().front()), its
  /// items in `layout`'s structs and units. Checks every item it uses against
  /// the team's table and the layout (SetupError naming the item): the
  /// written ones and CMD_VEL, CMD_KICKER, CMD_GRABBER are required;
  /// LAST_CMD_VEL, CMD_HWERRORS and CMD_SETPOSE are served when the layout
  /// describes them. `db` and `layout` must outlive the handler.
  HwComm(std::shared_ptr<const frames::MessageSet> set, Nanos ec, Send send, Clock clock, rtdb::Database& db,
         const rtdb::Layout& layout, int space);
  ~HwComm();
  HwComm(const HwComm&) = delete;
  HwComm& operator=(const HwComm&) = delete;

  /// A received frame with its receive timestamp.
  void on_frame(const frames::CanFrame& frame, Nanos rx_time);
  /// The bus's bit rate, for the TM's wire time (1 Mbit/s unless set): the
  /// asynchronous window opens when the TM has left the wire (frames/ftt_slot.hpp).
  void set_bit_rate(std::uint32_t bit_rate);
  /// What a received frame's stamp marks (frames::StampAt): its first bit
  /// (vcan, the default) or its end of frame (a real can0, canhil's timed
  /// wire); the EC starts at the TM's stamp, or its wire time before it.
  void set_stamps(frames::StampAt stamps) noexcept { ftt_.stamps = stamps; }
  /// When the handler must act next (the asynchronous window's opening, its M6 slot), or kNever.
  Nanos next_deadline() const noexcept { return std::min(async_at_, m6_at_); }
  /// Acts at `now` (call at or after next_deadline()).
  void on_time(Nanos now);

  const HwCommStats& stats() const noexcept { return stats_; }
  /// Frames of message `name` received and sent so far (0 for a name the set does not have).
  std::uint64_t received(std::string_view name) const noexcept;
  std::uint64_t sent(std::string_view name) const noexcept;
  /// Multi-line summary for the end of a run.
  std::string summary() const;

 private:
  struct Items;
  void send(const frames::CanFrame& f, const frames::MessageCodec& message);
  std::size_t index_of(const frames::MessageCodec& m) const noexcept;
  void on_tm(const frames::Tm& tm, Nanos ec_start);
  void on_error_frame(const frames::CanFrame& f);  // ec_start: frames::ec_start of its stamp
  void send_sporadic(Nanos slot);                  // kicker, grabber, pose: in the asynchronous window
  void on_pose(const frames::M4_2& m4);
  void latency(Nanos rx_time);
  void write_hwerrors();

  std::shared_ptr<const frames::MessageSet> set_;
  Nanos ec_;
  Send send_;
  Clock clock_;
  std::unique_ptr<Items> items_;  // the RTDB items in the team's layout, resolved once
  HwCommStats stats_;
  frames::SyncSlot m6_slot_;
  Nanos m6_at_ = kNever;     // the M6 slot to serve (the last TM's may be replaced by the next)
  Nanos async_at_ = kNever;  // the asynchronous window's opening to serve (likewise)
  Nanos tm_wire_{0};         // the TM's worst-case wire time
  frames::FttConfig ftt_;    // the EC, the bit rate and what stamps mark, for the EC's start (frames::ec_start)
  bool have_tm_ = false;
  std::uint16_t last_ec_ = 0;
  bool have_m4_1_ = false;
  frames::M4_1 m4_1_{};
  bool have_pose_ = false;
  double last_x_ = 0, last_y_ = 0, last_heading_ = 0;
  Nanos last_m7_ = kLongAgo;
  Nanos last_m5_ = kLongAgo;
  double last_grabber_ = -1;  // the fraction last sent; -1: none yet
  std::uint8_t m6_seq_ = 0;
  frames::M10 m10_{};
};

}  // namespace canhil::laptop
