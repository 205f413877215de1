// tests/support/child_process.hpp — a program run in the background for the
// vcan tests (the emulator, the handler), its output captured to a file;
// stop() sends SIGINT (its Ctrl-C) and waits; a child that has not ended 60 s
// later is killed (SIGKILL), with every process it started, and fails the
// test, so a hang is reported rather than holding the suite until its time
// limit or leaving a process behind on the bus of the next test. A sanitizer's report in the
// child's output (ASan, UBSan, TSan builds) fails the test that ran it, so a
// finding in a child process is never lost behind an unchecked exit status.
#pragma once

#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <optional>
#include <string>

namespace canhil::test {

class ChildProcess {
 public:
  ChildProcess(const std::string& command, std::string log_file) : log_(std::move(log_file)) {
    std::remove(log_.c_str());  // a previous run's output must never be read as this one's
    pid_ = fork();
    if (pid_ == 0) {
      setpgid(0, 0);  // its own group: a kill reaches what it started too
      const std::string full = "exec " + command + " > " + log_ + " 2>&1";  // exec: the signal reaches it
      execl("/bin/sh", "sh", "-c", full.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    if (pid_ > 0) setpgid(pid_, pid_);  // as the child does: whichever comes first
  }
  ~ChildProcess() { stop(); }
  /// The child's process id (the command's own, since the shell execs it), or -1 once stopped.
  int pid() const noexcept { return pid_; }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  /// SIGINT, then waits; returns the wait status (or -1 if already stopped).
  int stop() { return kill_with(SIGINT); }
  /// Waits up to `limit` for the process to end by itself: its wait status,
  /// or nothing while it still runs (stop() or the destructor ends it then).
  std::optional<int> wait_end(std::chrono::milliseconds limit) {
    if (pid_ <= 0) return std::nullopt;
    int status = 0;
    for (auto waited = std::chrono::milliseconds(0); waited <= limit; waited += std::chrono::milliseconds(100)) {
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        check_sanitizers();
        return status;
      }
      usleep(100'000);
    }
    return std::nullopt;
  }
  /// Sends `sig` (e.g. SIGKILL: the process dies without cleaning up) and reaps it.
  int kill_with(int sig) {
    if (pid_ <= 0) return -1;
    ::kill(pid_, sig);
    int status = 0;
    constexpr int kTenthsToEnd = 600;  // 60 s: a sanitized child in the VM runner ends well within it
    int tenths = 0;
    while (waitpid(pid_, &status, WNOHANG) == 0) {
      if (++tenths > kTenthsToEnd) {
        ADD_FAILURE() << log_ << ": the process did not end within 60 s of signal " << sig
                      << "; killed (SIGKILL). Its output:\n"
                      << output();
        ::kill(-pid_, SIGKILL);  // and whatever it started: nothing of it may go on into the next test
        waitpid(pid_, &status, 0);
        break;
      }
      usleep(100'000);
    }
    pid_ = -1;
    check_sanitizers();
    return status;
  }
  void check_sanitizers() const {
    const std::string out = output();
    for (const char* report :
         {"WARNING: ThreadSanitizer", "ERROR: AddressSanitizer", "ERROR: LeakSanitizer", "runtime error:"}) {
      if (out.find(report) != std::string::npos) ADD_FAILURE() << log_ << " has a sanitizer report:\n" << out;
    }
  }
  std::string output() const {
    std::string out;
    if (FILE* f = std::fopen(log_.c_str(), "r")) {
      char buf[512];
      while (std::fgets(buf, sizeof buf, f) != nullptr) out += buf;
      std::fclose(f);
    }
    return out;
  }

 private:
  pid_t pid_ = -1;
  std::string log_;
};

}  // namespace canhil::test
