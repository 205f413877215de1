// canhil/base/pi_mutex.hpp — a mutex with priority inheritance, for state a
// real-time thread shares with a thread of the normal scheduler.
//
// A real-time run's node threads (SCHED_FIFO) and its physics thread (the
// normal scheduler) exchange a few numbers under a lock. With a plain mutex,
// a physics thread preempted while it holds the lock (a busy machine: a build
// beside the run) keeps the node thread waiting for as long as it is not
// scheduled: a priority inversion, and frames late by milliseconds. With
// PTHREAD_PRIO_INHERIT the holder runs at the waiter's priority until it lets
// go. Satisfies Lockable (std::lock_guard, std::unique_lock,
// std::condition_variable_any); not copyable or movable.
#pragma once

#include <pthread.h>

#include "canhil/base/demand.hpp"

namespace canhil {

class PiMutex {
 public:
  PiMutex() {
    pthread_mutexattr_t attributes;
    pthread_mutexattr_init(&attributes);
    pthread_mutexattr_setprotocol(&attributes, PTHREAD_PRIO_INHERIT);
    const int failed = pthread_mutex_init(&mutex_, &attributes);
    pthread_mutexattr_destroy(&attributes);
    CANHIL_DEMAND(failed == 0, "a priority-inheriting mutex could not be made");
  }
  ~PiMutex() { pthread_mutex_destroy(&mutex_); }
  PiMutex(const PiMutex&) = delete;
  PiMutex& operator=(const PiMutex&) = delete;

  void lock() { pthread_mutex_lock(&mutex_); }
  bool try_lock() { return pthread_mutex_trylock(&mutex_) == 0; }
  void unlock() { pthread_mutex_unlock(&mutex_); }

 private:
  pthread_mutex_t mutex_;
};

}  // namespace canhil
