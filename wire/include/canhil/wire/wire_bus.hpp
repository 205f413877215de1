// canhil/wire/wire_bus.hpp — a CAN bus's physics: wire time, arbitration,
// controllers with transmit queues, error confinement and bus-off, and faults.
//
// Pure and clock-injected: the caller says what time it is (submit, advance),
// the bus says what happened by then, in order (WireEvent), and when it next
// has something to say (next_event). It never reads a clock and holds no
// socket, so the in-memory bus of a virtual-time run and the user-space bus's
// broker in real time use the same model and give the same order.
//
// The model (docs/wire.md says it for users):
// - A controller is one CAN controller on the bus (an emulated node; a
//   program's adapter). It sends its own frames in the order given (one
//   transmit buffer fed from a FIFO queue, as SocketCAN's qdisc feeds a
//   can-dev driver); a full queue refuses the frame (the socket's ENOBUFS).
// - A frame takes its exact bits (frames::count_bits: stuffing on its real bit
//   stream, CRC included; FD's data phase at the data bit rate), or the worst
//   case of its shape. Its receivers have it at the end of its end-of-frame
//   field; the bus is free 3 bits later (intermission), when every controller's
//   next frame takes part in arbitration: the lowest identifier wins, bit by bit
//   (frames::arbitration_key: a base frame before an extended one with the
//   same 11 bits, a data frame before a remote one); equal keys go in the
//   order they were given. A frame given at the very instant arbitration
//   starts takes part in it. An error-passive controller that has just sent
//   waits 8 bits more (suspend transmission).
// - Errors (from the fault rules, or a frame nobody acknowledges) end the
//   frame at the bit where they are seen: an error flag (6 bits, 12 with the
//   other nodes' flags superposed), the 8-bit delimiter and the intermission
//   follow; the transmitter sends the frame again at the next arbitration.
//   Counters as confinement.hpp; each controller that sees the error reports
//   it as a can-dev driver does (error_frames.hpp).
// - Bus-off: the controller's frame on the wire is dropped, its queue kept; it
//   sends and receives nothing. After its restart delay (or restart()), it
//   needs 128 occurrences of 11 consecutive recessive bits on the bus (the
//   tail of every frame is one: ACK delimiter, end of frame, intermission),
//   then it is error-active with both counters 0 and reports CAN_ERR_RESTARTED.
// Not modelled: the analogue layer, bit timing segments and resynchronisation,
// propagation delay, overload frames.
//
// Deterministic: the same calls give the same events (the faults' draws come
// from `seed`). Not thread-safe.
#pragma once

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "canhil/base/ring.hpp"
#include "canhil/base/time.hpp"
#include "canhil/frames/frame.hpp"
#include "canhil/frames/wire.hpp"
#include "canhil/wire/confinement.hpp"
#include "canhil/wire/wire_fault.hpp"

namespace canhil::wire {

using ControllerId = std::uint32_t;

struct WireConfig {
  std::uint32_t bit_rate = 1'000'000;  ///< nominal (arbitration) bit rate, bit/s; > 0
  std::uint32_t data_bit_rate = 0;     ///< CAN FD's data phase (BRS); 0: the nominal rate
  enum class Bits : std::uint8_t { kExact, kWorstCase };
  Bits bits = Bits::kExact;  ///< a frame's exact bits, or the most its shape can take
  std::uint64_t seed = 1;    ///< the fault rules' random draws
};

struct ControllerOptions {
  std::size_t queue_frames = 64;  ///< frames that may wait to be sent; one more is refused
  /// After bus-off, when the recovery (128 x 11 recessive bits) begins:
  /// nullopt only on restart() (the kernel's restart-ms 0); a delay, that
  /// long after (restart-ms); Nanos{0} at once (a microcontroller's automatic recovery).
  std::optional<Nanos> restart_delay = Nanos{0};
};

/// What happened on the bus.
struct WireEvent {
  WireEvent() = default;
  /// A kFrame event, built in place. Of `f`'s bytes it reads those it has
  /// (a classic frame: the 8 a classic frame holds); the rest are 0.
  WireEvent(ControllerId sender, std::uint64_t frame_tag, Nanos first_bit, Nanos end, const frames::WireFrame& f)
      : controller(sender), tag(frame_tag), start(first_bit), at(end) {
    frame.id = f.id;
    frame.extended = f.extended;
    frame.remote = f.remote;
    frame.fd = f.fd;
    frame.brs = f.brs;
    frame.esi = f.esi;
    frame.len = f.len;
    frame.len8_dlc = f.len8_dlc;
    const std::size_t held = f.fd ? std::min<std::size_t>(f.len, frame.data.size()) : frames::kMaxDataBytes;
    std::copy_n(f.data.begin(), held, frame.data.begin());
  }
  enum class Kind : std::uint8_t {
    kFrame,  ///< a frame's last bit has passed: its receivers have it
    kError,  ///< a controller reports an error or a change of state (Linux's error frame)
  };
  Kind kind = Kind::kFrame;
  ControllerId controller = 0;  ///< kFrame: the sender; kError: the reporting controller
  std::uint64_t tag = 0;        ///< kFrame: the sender's tag (submit); kBabbleTag for a babbling node's frame
  Nanos start{0};               ///< kFrame: its first bit
  Nanos at{0};                  ///< kFrame: its end of frame; kError: when it was seen
  frames::WireFrame frame;      ///< kFrame
  frames::CanFrame error;       ///< kError: kind kError, id the CAN_ERR_* classes, data[1..7]
  /// kFrame: controllers on the bus that did not receive it (bus-off or cut
  /// off), besides the sender; removed ones are not on the bus, and not here.
  std::vector<ControllerId> missed;
};
inline constexpr std::uint64_t kBabbleTag = ~std::uint64_t{0};

struct ControllerStatus {
  std::string name;
  ControllerState state = ControllerState::kErrorActive;
  std::uint16_t tec = 0;
  std::uint16_t rec = 0;
  std::uint64_t sent = 0;      ///< frames sent whole
  std::uint64_t received = 0;  ///< frames received whole
  std::uint64_t errors = 0;    ///< errors it saw (each one error report)
  std::uint64_t bus_offs = 0;
  std::uint64_t restarts = 0;
  std::uint64_t refused = 0;  ///< frames refused on a full queue
  std::uint64_t lost = 0;     ///< frames dropped unsent: the one on the wire when it was forced bus-off
  std::size_t queued = 0;     ///< frames waiting, the one on the wire included
  bool connected = true;      ///< false while a cut-cable fault holds
  bool recovering = false;    ///< bus-off and counting recessive bits
};

struct WireStats {
  std::uint64_t frames = 0;        ///< frames carried whole
  std::uint64_t error_frames = 0;  ///< errors on the bus (one per failed frame)
  Nanos busy{0};                   ///< time the bus carried bits (frames, errors, intermissions)
  Nanos until{0};                  ///< the time the bus has been advanced to
  double load() const noexcept {
    return until.count() > 0 ? static_cast<double>(busy.count()) / static_cast<double>(until.count()) : 0.0;
  }
};

class WireBus {
 public:
  explicit WireBus(const WireConfig& config);
  WireBus(const WireBus&) = delete;
  WireBus& operator=(const WireBus&) = delete;

  const WireConfig& config() const noexcept { return config_; }
  ControllerId add_controller(std::string name, const ControllerOptions& options = {});
  /// Takes a controller off the bus for good (its endpoint closed): its
  /// queue is dropped, it sends, receives and acknowledges nothing more.
  void remove_controller(ControllerId controller);
  std::size_t controllers() const noexcept { return controllers_.size(); }

  enum class Submit : std::uint8_t { kQueued, kQueueFull, kBusOff };
  /// Queues `frame` on `controller` at `now` (not before the last advance);
  /// `tag` comes back in its kFrame event. A bus-off controller still queues
  /// (its frames wait for the recovery), as a stopped SocketCAN queue does;
  /// kBusOff says so.
  Submit submit(ControllerId controller, const frames::WireFrame& frame, Nanos now, std::uint64_t tag = 0);
  /// The same for a classic frame as a bus endpoint has it (data or remote;
  /// not an error frame), put in the queue as it is read: no WireFrame is
  /// made of it first.
  Submit submit(ControllerId controller, const frames::CanFrame& frame, Nanos now, std::uint64_t tag = 0);

  /// Runs the bus up to `now`; appends what happened by then, in order of
  /// time (ties: the order it happened in), to `out`.
  void advance(Nanos now, std::vector<WireEvent>& out) {
    if (next_event() <= now) happen(now, out);
    if (now > now_) {
      now_ = now;
      if (!calm_) next_stale_ = true;  // calm, the next event is the chosen frame's end, whatever the time
    }
    stats_.until = now_;
  }
  /// The earliest time advance() has something to do; kNever when idle.
  Nanos next_event() const {
    if (next_stale_) {
      next_ = earliest_due();
      next_stale_ = false;
    }
    return next_;
  }

  /// Restarts a bus-off controller's recovery now (`ip link set can0 type
  /// can restart`); false when it is not bus-off.
  bool restart(ControllerId controller, Nanos now);
  void set_restart_delay(ControllerId controller, std::optional<Nanos> delay);
  /// A fault rule from `rule.from` to `rule.until` (wire_fault.hpp); false,
  /// and nothing added, when it names no controller where its kind needs one
  /// (bus-off, babbling, cut) or one this bus does not have.
  bool add_fault(const FaultRule& rule);
  /// Ends every fault rule (live: `canhil bus fault clear`).
  void clear_faults(Nanos now);

  ControllerStatus status(ControllerId controller) const;
  const WireStats& stats() const noexcept { return stats_; }
  /// Frames waiting on all controllers, the one on the wire included.
  std::size_t queued() const noexcept;

 private:
  // A frame waiting, each in two cache lines: the first holds all a classic
  // frame's way through the bus reads (the frame's header and 8 bytes come
  // after the rest), the second only an FD frame's further bytes.
  struct alignas(64) Queued {
    std::uint64_t key = 0;  // frames::arbitration_key
    std::uint64_t seq = 0;  // order given
    std::uint64_t tag = 0;
    Nanos given{0};
    frames::FrameBits bits;  // frames::count_bits, counted when given (the frame is at hand then)
    frames::WireFrame frame;
  };
  // What a frame's way through the bus reads first, in its first cache line
  // (a run's frames come between physics steps: each visit is a cold one).
  struct alignas(64) Controller {
    base::Ring<Queued> queue;  // no allocation per frame, as a deque's blocks would
    Nanos not_before{0};       // suspend transmission after an error-passive send
    Confinement confinement;
    ControllerState reported = ControllerState::kErrorActive;  // last state told
    bool gone = false;                                         // remove_controller()
    std::uint64_t sent = 0;                                    // frames sent whole (ControllerStatus::sent)
    ControllerOptions options;
    ControllerStatus counts;  // all but `sent`
    std::string name;
    Nanos restart_at = kNever;      // bus-off: when the recovery begins
    bool recovering = false;        // bus-off: counting 11-bit recessive runs
    std::uint32_t occurrences = 0;  // of 11 recessive bits, so far
    Nanos run_from{0};              // where this controller's current count of recessive bits began
    Nanos cut_busy_until{0};        // cut off: its own stub is busy with an attempt until then
    // While the bus is calm, its frames received are counted from these:
    // the bus's frames and its own sent when the calm began (calm_received).
    std::uint64_t calm_frames = 0;
    std::uint64_t calm_sent = 0;
  };
  // A frame (or babble frame) on the wire.
  struct OnWire {
    ControllerId from = 0;
    std::uint64_t key = 0;  // its arbitration key
    bool babble = false;    // the frame is babble_ (a babbling node's, or one whose sender was removed)
    ErrorPlan plan;         // how it ends
    Nanos start{0};
    Nanos end{0};      // its end of frame, or when its error is seen
    Nanos free_at{0};  // the bus is free for the next arbitration
  };

  // A slot at the back of `k`'s queue for a frame given, or nullptr when the queue is full (counted).
  Queued* slot(Controller& k);
  // The rest of submit(), once q's frame is in it.
  Submit given(ControllerId controller, Queued& q, Nanos now, std::uint64_t tag);

  // Bits as time: by one multiplication where a bit is a whole number of
  // nanoseconds (every usual rate), else as frames::bits_to_time divides.
  // The frame on the wire, where it lies: its sender's queue's head, or babble_.
  const Queued& sent(const OnWire& w) const noexcept { return w.babble ? babble_ : controllers_[w.from].queue.front(); }
  Nanos bits(std::uint32_t n) const noexcept {
    return bit_ns_ != 0 ? Nanos{bit_ns_ * n} : frames::bits_to_time(n, config_.bit_rate);
  }
  Nanos frame_bits(frames::FrameBits b) const noexcept {
    if (bit_ns_ != 0 && (b.fast == 0 || fast_bit_ns_ != 0)) return Nanos{bit_ns_ * b.nominal + fast_bit_ns_ * b.fast};
    return frames::bits_to_time(b, config_.bit_rate, config_.data_bit_rate);
  }
  Nanos frame_time(const frames::WireFrame& f, std::uint32_t bit_count) const noexcept;
  // The one thing due at `at` (the earliest), done.
  void step(Nanos at, std::vector<WireEvent>& out);
  // When controller `c` could start its next frame (kNever: it cannot).
  Nanos ready_at(ControllerId c) const noexcept {
    if (!calm_) return ready_at_with_rules(c);
    // Calm: nobody bus-off, no rule: nobody babbles, is cut off or stuck.
    return controllers_[c].queue.empty() ? kNever : calm_ready(c);
  }
  // Calm, a controller with frames waiting: when its head could start.
  Nanos calm_ready(ControllerId c) const noexcept { return std::max(std::max(idle_from_, now_), fronts_[c].at); }
  Nanos ready_at_with_rules(ControllerId c) const noexcept;
  // The events due by `now`, in order (advance()).
  void happen(Nanos now, std::vector<WireEvent>& out);
  Nanos bus_due() const noexcept;
  Nanos earliest_due() const;  // next_event(), worked out
  bool arbitrate(Nanos at);
  // Puts `from`'s head (or a babbling node's frame) on the wire from `at`: its bits, how it ends.
  void put_on_wire(ControllerId from, std::uint64_t key, const FaultRule* babble, Nanos at);
  void finish(std::vector<WireEvent>& out);
  void fail(OnWire& w, std::vector<WireEvent>& out);
  // Tells controller `c`'s error (`classes` 0: only a change of state, if any).
  void report(ControllerId c, Nanos at, std::uint32_t classes, std::uint8_t kind, std::uint8_t location,
              std::vector<WireEvent>& out);
  void enter_bus_off(ControllerId c, Nanos at);
  void recessive_run_ends(Nanos at);  // a dominant bit at `at`: every recovering controller counts its run
  Nanos recovery_due(const Controller& k) const noexcept;
  void recover(ControllerId c, Nanos at, std::vector<WireEvent>& out);
  bool acknowledged(ControllerId from) const noexcept;
  // A calm bus: no fault rule, nobody bus-off, every receive counter 0. A
  // frame's receivers then change nothing but their count of frames
  // received, which is kept lazily: what it was when the calm began, plus
  // the frames carried since that were not their own.
  std::uint64_t calm_received(const Controller& k) const noexcept {
    return calm_ && !k.gone ? (stats_.frames - k.calm_frames) - (k.sent - k.calm_sent) : 0;
  }
  // Calm, the next frame on the wire is chosen as soon as it is known, with
  // its start in the future (the bus falls idle then), and chosen again
  // whenever what it depends on changes before it starts (a frame given by
  // then, a controller coming or going): the same frame as arbitration at
  // its start would choose, since calm arbitration changes nothing else
  // (no draws, nobody recovering). The bus's next event is then a frame's end,
  // never an idle instant with nothing to tell.
  void choose_again(Nanos now);
  void end_calm() noexcept;    // the lazy counts made whole; calm_ false
  void begin_calm() noexcept;  // calm_ true, the lazy counts from now
  // Off the bus at `t`: removed, or cut off by a fault.
  bool off_bus(ControllerId c, Nanos t) const noexcept { return controllers_[c].gone || faults_.cut(c, t); }
  // The fault rules' own moments (wire_bus_faults.cpp).
  void fault_change(Nanos at, std::vector<WireEvent>& out);
  void stuck_tick(Nanos at, std::vector<WireEvent>& out);
  Nanos cut_due(ControllerId c) const noexcept;
  void cut_attempt(ControllerId c, Nanos at, std::vector<WireEvent>& out);

  // What every frame's way through the bus reads comes first, in four
  // cache lines (a run's frames come between physics steps: each line is a
  // cold one): the controllers and the bit's time; the frame on the wire;
  // the bus's times and flags; its counts and whether it has fault rules.
  WireConfig config_;
  std::int64_t bit_ns_ = 0;       // a nominal bit's nanoseconds when whole, else 0
  std::int64_t fast_bit_ns_ = 0;  // a data-phase bit's, likewise
  std::vector<Controller> controllers_;
  std::optional<OnWire> wire_;
  Nanos idle_from_{0};       // the bus is free from then (arbitration then or at the next frame given)
  Nanos recessive_from_{0};  // the bus has been recessive since then (no SOF, no flag)
  Nanos now_{0};
  std::uint64_t seq_ = 0;
  // Which controllers have frames queued (bit c), when there are at most 64:
  // arbitration and the bus's next start look at those only, unless a fault
  // rule (a babbling node sends with nothing queued) asks for everyone.
  std::uint64_t waiting_ = 0;
  // next_event(), asked far more often than anything changes: kept until a change.
  mutable Nanos next_ = kNever;
  std::size_t present_ = 0;  // controllers not removed
  mutable bool next_stale_ = true;
  bool calm_ = true;
  // A controller's restart and recovery, and a cut controller's attempts,
  // need a look at every controller at every event; a bus where no
  // controller ever went bus-off and no fault rule was given has none.
  bool ever_bus_off_ = false;
  WireStats stats_;
  Nanos stuck_tick_at_ = kNever;  // a stuck-dominant bus's next 8-bit sequence
  Faults faults_;                 // its rules first: the line before holds their count
  Queued babble_;                 // the frame on the wire when it is no queue's

  // What a calm arbitration reads of each controller with frames waiting,
  // side by side (one look at a few cache lines, not two lines of each
  // controller): its head's key and order, and the earliest it may start
  // (its head given, its suspend transmission over). Kept by front_changed().
  struct Front {
    std::uint64_t key = 0;
    std::uint64_t seq = 0;
    Nanos at{0};
  };
  std::vector<Front> fronts_;  // by controller; read only while its queue has frames
  // After every change to a queue or a controller's not_before.
  void front_changed(ControllerId c) noexcept {
    const Controller& k = controllers_[c];
    if (k.queue.empty()) return;
    const Queued& head = k.queue.front();
    fronts_[c] = Front{head.key, head.seq, std::max(k.not_before, head.given)};
  }
  void queue_changed(ControllerId c) noexcept {
    front_changed(c);
    if (c >= 64) return;
    const std::uint64_t bit = std::uint64_t{1} << c;
    waiting_ = controllers_[c].queue.empty() ? waiting_ & ~bit : waiting_ | bit;
  }
  template <class F>
  void each_sender(F&& f) const {
    if (controllers_.size() > 64 || !faults_.rules().empty()) {
      for (ControllerId c = 0; c < controllers_.size(); ++c) f(c);
      return;
    }
    for (std::uint64_t w = waiting_; w != 0; w &= w - 1) f(static_cast<ControllerId>(std::countr_zero(w)));
  }
  bool timers_possible() const noexcept { return ever_bus_off_ || !faults_.rules().empty(); }
};

}  // namespace canhil::wire
