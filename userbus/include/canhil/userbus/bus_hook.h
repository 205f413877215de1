/* canhil/userbus/bus_hook.h — what the user-space bus's preload
 * (libcanhil-bus.so) tells the process it is loaded into, beyond the sockets
 * it serves: whether an interface is on the bus, when a frame has reached
 * every socket, what a socket has waiting, an interface's wire and counts,
 * and a socket that is a controller of its own. canhil's lockstep and reports
 * ask (can_nodes: on_user_space_bus, DeliveryFence, SocketCanBus::waiting).
 *
 * The preload exports these functions with C linkage. canhil does not link
 * the preload: it looks them up once with dlsym(RTLD_DEFAULT, name)
 * (canhil::preload::any_symbol in canhil/base/preload.hpp, or
 * canhil::userbus::hooks() in C++), and a null pointer means the process is
 * not on a user-space bus: the kernel's SocketCAN serves it.
 *
 * Every function may be called from any thread at any time; none blocks. */
#ifndef CANHIL_USERBUS_BUS_HOOK_H
#define CANHIL_USERBUS_BUS_HOOK_H

#ifdef __cplusplus
extern "C" {
#endif

/* 1 when interface `name` is on the user-space bus this process runs on, else 0. */
int canhil_userbus_interface(const char* name);
typedef int (*canhil_userbus_interface_fn)(const char* name);
#define CANHIL_USERBUS_INTERFACE "canhil_userbus_interface"

/* The broker's rounds (userbus::State::rounds) on the bus this process runs
 * on: odd while the broker hands a round of frames to their sockets, so a
 * frame read on one socket is in every socket once the count is even, or past
 * the odd value it had after the read. Without a bus 1, a round that never
 * ends: a bus gone delivers nothing. */
unsigned long long canhil_userbus_rounds(void);
typedef unsigned long long (*canhil_userbus_rounds_fn)(void);
#define CANHIL_USERBUS_ROUNDS "canhil_userbus_rounds"

/* How many frames the broker has given bus socket `fd` that no read has taken
 * yet (one being handed over shows once it is in the socket), or -1 when `fd`
 * is not a bus socket. */
long long canhil_userbus_waiting(int fd);
typedef long long (*canhil_userbus_waiting_fn)(int fd);
#define CANHIL_USERBUS_WAITING "canhil_userbus_waiting"

/* Gives interface `name` a wire (userbus/state.hpp's Interface; bit_rate 0:
 * instant again), as `canhil bus link NAME bitrate ...` does, and returns
 * once the broker has taken it (one round trip): 0, or -ENODEV when the
 * interface is not on the bus. `driven`: the wire's clock is the caller's
 * (a lockstep run's), moved by canhil_userbus_wire_time, not the broker's. */
int canhil_userbus_set_wire(const char* name, unsigned int bit_rate, unsigned int data_bit_rate, int restart_ms,
                            unsigned int tx_queue, int driven);
typedef int (*canhil_userbus_set_wire_fn)(const char* name, unsigned int bit_rate, unsigned int data_bit_rate,
                                          int restart_ms, unsigned int tx_queue, int driven);
#define CANHIL_USERBUS_SET_WIRE "canhil_userbus_set_wire"

/* Bus socket `fd` becomes a controller of its own on timed interfaces (an
 * emulated node is a board of its own), not one with every other socket of
 * its process; 0, or -1 when `fd` is not a bus socket. */
int canhil_userbus_own_controller(int fd);
typedef int (*canhil_userbus_own_controller_fn)(int fd);
#define CANHIL_USERBUS_OWN_CONTROLLER "canhil_userbus_own_controller"

/* What interface `name` has carried: counts[0] frames, [1] copies dropped at
 * full receivers, [2] error frames on its wire, [3] ns its wire carried bits,
 * [4] ns since its wire began, [5] frames its wire delivered whole, [6] a
 * driven wire's next event in its own time (ns; 2^63 - 1: none), published
 * before the frame that moved it is counted in [0]. 1 with a wire, 0
 * without, -1 when it is not on the bus. */
int canhil_userbus_wire_counts(const char* name, unsigned long long* counts);
typedef int (*canhil_userbus_wire_counts_fn)(const char* name, unsigned long long* counts);
#define CANHIL_USERBUS_WIRE_COUNTS "canhil_userbus_wire_counts"

/* Runs interface `name`'s driven wire to `time_ns` (its own time) and
 * returns once what it delivered by then is in the sockets (one round
 * trip): 0, or -ENODEV. */
int canhil_userbus_wire_time(const char* name, long long time_ns);
typedef int (*canhil_userbus_wire_time_fn)(const char* name, long long time_ns);
#define CANHIL_USERBUS_WIRE_TIME "canhil_userbus_wire_time"

#ifdef __cplusplus
}

#include "canhil/base/preload.hpp"

namespace canhil::userbus {

/// The preload's exports in this process, looked up once (the first call);
/// all null when the process is not on a user-space bus.
struct Hooks {
  canhil_userbus_interface_fn interface = nullptr;
  canhil_userbus_rounds_fn rounds = nullptr;
  canhil_userbus_waiting_fn waiting = nullptr;
  canhil_userbus_set_wire_fn set_wire = nullptr;
  canhil_userbus_own_controller_fn own_controller = nullptr;
  canhil_userbus_wire_counts_fn wire_counts = nullptr;
  canhil_userbus_wire_time_fn wire_time = nullptr;
  bool loaded() const noexcept { return interface != nullptr; }
};

/// This process's hooks (the preload is loaded before main() or never).
inline const Hooks& hooks() {
  static const Hooks found{
      ::canhil::preload::any_symbol<canhil_userbus_interface_fn>(CANHIL_USERBUS_INTERFACE),
      ::canhil::preload::any_symbol<canhil_userbus_rounds_fn>(CANHIL_USERBUS_ROUNDS),
      ::canhil::preload::any_symbol<canhil_userbus_waiting_fn>(CANHIL_USERBUS_WAITING),
      ::canhil::preload::any_symbol<canhil_userbus_set_wire_fn>(CANHIL_USERBUS_SET_WIRE),
      ::canhil::preload::any_symbol<canhil_userbus_own_controller_fn>(CANHIL_USERBUS_OWN_CONTROLLER),
      ::canhil::preload::any_symbol<canhil_userbus_wire_counts_fn>(CANHIL_USERBUS_WIRE_COUNTS),
      ::canhil::preload::any_symbol<canhil_userbus_wire_time_fn>(CANHIL_USERBUS_WIRE_TIME)};
  return found;
}

}  // namespace canhil::userbus
#endif

#endif /* CANHIL_USERBUS_BUS_HOOK_H */
