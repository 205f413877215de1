#include "canhil/can_nodes/medium.hpp"

#include <chrono>
#include <cstdint>

#include "canhil/can_nodes/socketcan_bus.hpp"
#include "canhil/userbus/bus_hook.h"

namespace canhil::can_nodes {

const char* medium_name(MediumKind kind) noexcept {
  switch (kind) {
    case MediumKind::kMemory:
      return "canhil's in-memory bus";
    case MediumKind::kUserSpace:
      return "canhil's user-space bus";
    case MediumKind::kKernel:
      break;
  }
  return "the kernel's SocketCAN";
}

SocketCanMedium::SocketCanMedium(std::string iface) : SocketCanMedium(std::move(iface), SocketCanOptions{}) {}
SocketCanMedium::SocketCanMedium(std::string iface, const SocketCanOptions& options)
    : iface_(std::move(iface)), options_(std::make_unique<SocketCanOptions>(options)) {}
SocketCanMedium::~SocketCanMedium() = default;

MediumKind socketcan_medium_kind(const std::string& iface) noexcept {
  // The bus's preload says so itself; canhil does not link it.
  const auto has = userbus::hooks().interface;
  return has != nullptr && has(iface.c_str()) != 0 ? MediumKind::kUserSpace : MediumKind::kKernel;
}

MediumKind SocketCanMedium::kind() const noexcept { return socketcan_medium_kind(iface_); }

std::unique_ptr<SocketCanBus> SocketCanMedium::open_socket() {
  auto socket = SocketCanBus::open(iface_, *options_);
  // Each endpoint is a controller of its own (bus.hpp), as each node is a board of its own.
  if (const auto own = userbus::hooks().own_controller) own(socket->fd());
  return socket;
}

std::unique_ptr<Endpoint> SocketCanMedium::open(const std::string& /*name*/) { return open_socket(); }

bool SocketCanMedium::set_wire(const Wire& wire) {
  const auto set = userbus::hooks().set_wire;
  if (kind() != MediumKind::kUserSpace || set == nullptr) return false;
  const auto& restart = wire.controller.restart_delay;
  const int restart_ms =
      restart ? static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(*restart).count()) : 0;
  return set(iface_.c_str(), wire.bit_rate, wire.data_bit_rate, restart && restart_ms == 0 ? 1 : restart_ms,
             static_cast<unsigned>(wire.controller.queue_frames), wire.driven ? 1 : 0) == 0;
}

void SocketCanMedium::drive(Nanos now) {
  if (const auto time = userbus::hooks().wire_time) time(iface_.c_str(), now.count());
}

MediumCounts SocketCanMedium::counts() const {
  MediumCounts c;
  unsigned long long n[7] = {};
  const auto read = userbus::hooks().wire_counts;
  const int timed = read != nullptr ? read(iface_.c_str(), n) : -1;
  if (timed < 0) return c;  // the kernel's: its counters are the interface's own (ip -s link)
  c.frames = n[0];
  c.error_frames = n[2];
  c.timed = timed == 1;
  c.load = n[4] > 0 ? static_cast<double>(n[3]) / static_cast<double>(n[4]) : 0.0;
  c.delivered = n[5];
  c.next_event = n[6] >= static_cast<unsigned long long>(INT64_MAX) ? kNever : Nanos{static_cast<std::int64_t>(n[6])};
  return c;
}

}  // namespace canhil::can_nodes
