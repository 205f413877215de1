// The bus's interfaces as programs ask for them: the interface ioctls, the
// names (if_nametoindex, if_indextoname), and what canhil itself asks of the
// bus it runs on (through dlsym: canhil does not link the preload). An
// interface that is not the bus's goes on to libc and the kernel.
#include <linux/can.h>
#include <linux/sockios.h>
#include <net/if.h>
#include <sys/ioctl.h>

#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstring>

#include "canhil/base/preload.hpp"
#include "canhil/userbus/bus_hook.h"
#include "preload_core.hpp"

namespace canhil::userbus::preload {

int interface_ioctl(unsigned long request, void* arg) noexcept {
  switch (request) {
    case SIOCGIFINDEX:
    case SIOCGIFNAME:
    case SIOCGIFFLAGS:
    case SIOCSIFFLAGS:
    case SIOCGIFMTU:
    case SIOCSIFMTU:
      break;
    default:
      return 1;
  }
  ifreq r{};
  if (!copy_in(&r, arg, sizeof r)) return 1;  // let the kernel answer EFAULT
  Interface* i = nullptr;
  if (request == SIOCGIFNAME) {
    i = interface_at(r.ifr_ifindex);
  } else {
    r.ifr_name[IFNAMSIZ - 1] = '\0';
    i = interface_named(r.ifr_name);
  }
  if (i == nullptr) return 1;
  switch (request) {
    case SIOCGIFINDEX:
      r.ifr_ifindex = i->index;
      break;
    case SIOCGIFNAME:
      std::memcpy(r.ifr_name, i->name, IFNAMSIZ);
      break;
    case SIOCGIFFLAGS:
      r.ifr_flags = static_cast<short>(IFF_NOARP | (i->up.load() != 0 ? (IFF_UP | IFF_RUNNING) : 0));
      break;
    case SIOCGIFMTU:
      r.ifr_mtu = static_cast<int>(i->mtu.load());
      break;
    case SIOCSIFMTU:  // vcan_change_mtu: only while down, only the two CAN MTUs
      if (i->up.load() != 0) return fail(EBUSY);
      if (r.ifr_mtu != static_cast<int>(CAN_MTU) && r.ifr_mtu != static_cast<int>(CANFD_MTU)) return fail(EINVAL);
      i->mtu.store(static_cast<std::uint32_t>(r.ifr_mtu));
      return 0;
    default: {  // SIOCSIFFLAGS: up or down, as `ip link set` (the bus is its user's: no capability asked)
      const std::uint32_t up = (r.ifr_flags & IFF_UP) != 0 ? 1 : 0;
      if (i->up.exchange(up) != up) interfaces_changed();
      return 0;
    }
  }
  return copy_out(arg, &r, sizeof r) ? 0 : fail(EFAULT);
}

}  // namespace canhil::userbus::preload

namespace bus = canhil::userbus::preload;

#pragma GCC visibility push(default)
extern "C" {

unsigned int if_nametoindex(const char* name) {
  if (name != nullptr && bus::bus_state(false) != nullptr) {
    if (const auto* i = bus::interface_named(name)) return static_cast<unsigned int>(i->index);
  }
  CANHIL_REAL(if_nametoindex);
  return real_if_nametoindex(name);
}

// canhil's side of the bus (canhil/userbus/bus_hook.h says what each tells).
int canhil_userbus_interface(const char* name) {
  return name != nullptr && bus::bus_state(false) != nullptr && bus::interface_named(name) != nullptr ? 1 : 0;
}

unsigned long long canhil_userbus_rounds() {
  const canhil::userbus::State* state = bus::bus_state(false);
  return state != nullptr ? state->rounds.load(std::memory_order_acquire) : 1;
}

long long canhil_userbus_waiting(int fd) {
  const canhil::userbus::Socket* s = bus::socket_of(fd);
  if (s == nullptr) return -1;
  const std::uint64_t taken = s->taken.load(std::memory_order_relaxed);
  const std::uint64_t given = s->received.load(std::memory_order_acquire);
  return given > taken ? static_cast<long long>(given - taken) : 0;
}

int canhil_userbus_set_wire(const char* name, unsigned int bit_rate, unsigned int data_bit_rate, int restart_ms,
                            unsigned int tx_queue, int driven) {
  if (name == nullptr || bus::bus_state(false) == nullptr) return -ENODEV;
  canhil::userbus::Interface* i = bus::interface_named(name);
  if (i == nullptr) return -ENODEV;
  i->driven.store(driven != 0 ? 1 : 0);
  i->next_due_ns.store(INT64_MAX);
  i->bit_rate.store(bit_rate);
  if (bit_rate == 0) {  // instant again: the interface's other settings kept for its next wire
    bus::interfaces_changed();
    return 0;
  }
  i->data_bit_rate.store(data_bit_rate);
  i->restart_ms.store(restart_ms);
  i->tx_queue.store(tx_queue == 0 ? 1 : tx_queue);
  bus::interfaces_changed();  // the broker takes them before this returns
  return 0;
}

int canhil_userbus_own_controller(int fd) {
  canhil::userbus::Socket* s = bus::socket_of(fd);
  if (s == nullptr) return -1;
  s->lock.lock();
  s->seq.fetch_add(1, std::memory_order_acq_rel);
  s->flags |= canhil::userbus::kOwnController;
  s->seq.fetch_add(1, std::memory_order_release);
  s->lock.unlock();
  return 0;
}

int canhil_userbus_wire_counts(const char* name, unsigned long long* counts) {
  const canhil::userbus::Interface* i =
      name != nullptr && bus::bus_state(false) != nullptr ? bus::interface_named(name) : nullptr;
  if (i == nullptr || counts == nullptr) return -1;
  counts[0] = i->frames.load();
  counts[1] = i->dropped.load();
  counts[2] = i->error_frames.load();
  counts[3] = i->busy_ns.load();
  counts[4] = i->wire_ns.load();
  counts[5] = i->delivered.load(std::memory_order_acquire);
  counts[6] = static_cast<unsigned long long>(i->next_due_ns.load(std::memory_order_acquire));
  return i->bit_rate.load() != 0 ? 1 : 0;
}

int canhil_userbus_wire_time(const char* name, long long time_ns) {
  const canhil::userbus::Interface* i =
      name != nullptr && bus::bus_state(false) != nullptr ? bus::interface_named(name) : nullptr;
  if (i == nullptr) return -ENODEV;
  canhil::userbus::ControlRequest r{canhil::userbus::kControlWireTime};
  r.ifindex = i->index;
  r.time_ns = time_ns;
  return bus::ask_broker(r);
}

char* if_indextoname(unsigned int index, char* name) {
  if (bus::bus_state(false) != nullptr) {
    if (const auto* i = bus::interface_at(static_cast<int>(index))) {
      std::memcpy(name, i->name, IF_NAMESIZE);
      return name;
    }
  }
  CANHIL_REAL(if_indextoname);
  return real_if_indextoname(index, name);
}

}  // extern "C"
#pragma GCC visibility pop
