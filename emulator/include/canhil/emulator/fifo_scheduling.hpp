// canhil/emulator/fifo_scheduling.hpp — real-time scheduling for the threads that send
// frames on time (canhil run's masters and nodes, canhil bench's bare loop),
// and locked memory for their process.
#pragma once

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <cstring>
#include <string>

namespace canhil::emulator {

// SCHED_FIFO for the calling thread (the nodes' loop) while it lives: a frame
// due is sent as soon as its timer fires, ahead of the physics thread and
// anything else on the machine. `problem` says why not, when it could not.
class FifoScheduling {
 public:
  explicit FifoScheduling(int priority) {
    if (priority <= 0) return;
    pthread_getschedparam(pthread_self(), &old_policy_, &old_param_);
    sched_param param{};
    param.sched_priority = priority;
    if (const int err = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param); err != 0) {
      problem = std::string("cannot run the nodes at SCHED_FIFO priority ") + std::to_string(priority) + " (" +
                std::strerror(err) + "; needs root or CAP_SYS_NICE): frame timing will follow the machine's load";
      return;
    }
    changed_ = true;
  }
  ~FifoScheduling() {
    if (changed_) pthread_setschedparam(pthread_self(), old_policy_, &old_param_);
  }
  FifoScheduling(const FifoScheduling&) = delete;
  FifoScheduling& operator=(const FifoScheduling&) = delete;
  std::string problem;

 private:
  int old_policy_ = SCHED_OTHER;
  sched_param old_param_{};
  bool changed_ = false;
};

// The whole process's memory locked while it lives (mlockall is per process,
// not per thread): no page faults in a real-time loop. Best effort.
class MemoryLock {
 public:
  explicit MemoryLock(bool on) : locked_(on && mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {}
  ~MemoryLock() {
    if (locked_) munlockall();
  }
  MemoryLock(const MemoryLock&) = delete;
  MemoryLock& operator=(const MemoryLock&) = delete;

 private:
  bool locked_;
};

}  // namespace canhil::emulator
