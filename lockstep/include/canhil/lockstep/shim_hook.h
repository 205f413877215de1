/* canhil/lockstep/shim_hook.h — how another library preloaded beside the time
 * shim (libcanhil-timeshim.so) tells it what the shim cannot see by itself:
 * that a descriptor became readable, or that a thread sent CAN frames. A
 * preload that carries frames in user space (no kernel socket, so no AF_CAN
 * for the shim to recognise, and no kernel wake-up of a waiter) calls these.
 *
 * The shim exports both functions with C linkage. The other preload does not
 * link the shim: it looks them up once with dlsym(RTLD_DEFAULT, name)
 * (canhil::preload::any_symbol in canhil/base/preload.hpp), and a null
 * pointer means the shim is not loaded (the process runs in real time, and
 * there is nothing to tell):
 *
 *     static const auto sent = canhil::preload::any_symbol<canhil_shim_frames_sent_fn>("canhil_shim_frames_sent");
 *     if (sent != nullptr) sent(1);
 *
 * Both may be called from any thread, at any time, also when the process is
 * not in a lockstep run (they then do nothing); neither blocks. They are not
 * async-signal-safe in the first call of a thread (which may claim the
 * thread's slot on the board).
 *
 * The kernel's CAN sockets are the hooks' first user: the shim's own write(),
 * send(), sendto(), sendmsg() and sendmmsg() count what they wrote to an
 * AF_CAN socket through canhil_shim_frames_sent (lockstep/src/shim_can.cpp).
 * So a preload that handles a write itself must not also pass it down to
 * libc through the shim as a write to a kernel CAN socket, or the frame
 * counts twice. docs/lockstep.md says how the board uses both. */
#ifndef CANHIL_LOCKSTEP_SHIM_HOOK_H
#define CANHIL_LOCKSTEP_SHIM_HOOK_H

#ifdef __cplusplus
extern "C" {
#endif

/* The calling thread has sent `frames` CAN frames (count them once sent,
 * when the send succeeded). canhil moves the virtual clock only once every
 * frame the processes sent has been seen on the bus, so a frame counted here
 * is one canhil must see: on the kernel's bus through its sockets, on another
 * bus through that bus's own report to canhil. frames <= 0: nothing. */
void canhil_shim_frames_sent(long long frames);
typedef void (*canhil_shim_frames_sent_fn)(long long frames);

/* The run's virtual time (the board's, ns from the run's start, without the
 * clocks' bases), or -1 outside a lockstep run: a user-space bus stamps the
 * frames this process writes with it, so that a wire on the run's clock
 * takes each frame at the instant it was written. */
long long canhil_shim_board_now(void);
typedef long long (*canhil_shim_board_now_fn)(void);

/* Descriptor `fd` has become readable without the kernel waking anyone (a
 * user-space bus put a frame in a descriptor the shim's waits poll). Every
 * thread of the run that waits in virtual time (poll, select, epoll, a
 * blocking read, a sleep) checks its call again, in this process and the
 * others, as when canhil announces a change: a thread that waits for `fd`
 * finds it readable at the current virtual time. The descriptor itself is
 * not looked at today (every waiter checks what it waits for); it is part of
 * the call so that a finer wake-up needs no new hook. */
void canhil_shim_descriptor_readable(int fd);
typedef void (*canhil_shim_descriptor_readable_fn)(int fd);

/* canhil's own side (lockstep::Conductor), when the shim is preloaded into
 * canhil itself: from then on the process's clocks read `board` (the
 * conductor's board), while its waits stay real; NULL ends it. Returns 0.
 * Its presence also tells canhil that it runs under the shim. */
int canhil_timeshim_conduct(void* board);
typedef int (*canhil_timeshim_conduct_fn)(void* board);
#define CANHIL_TIMESHIM_CONDUCT "canhil_timeshim_conduct"

#ifdef __cplusplus
}
#endif

#endif /* CANHIL_LOCKSTEP_SHIM_HOOK_H */
