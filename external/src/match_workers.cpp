// Matches in worker processes (match_workers.hpp).
#include "canhil/external/match_workers.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <optional>

#include "canhil/base/setup_error.hpp"
#include "canhil/external/private_rtdb.hpp"

namespace canhil::external {
namespace {

// Lines from a worker: "p SEED SECONDS" (progress), "r JSON" (a record),
// "e TEXT" (play() threw SetupError). To a worker: "NUMBER SEED".
struct Worker {
  pid_t pid = -1;
  int to = -1;    // seeds to play
  int from = -1;  // lines back
  std::string buffer;
  std::optional<std::uint64_t> playing;
};

// `text` to a worker's pipe or back to the parent's: false when the other end
// is gone. The SIGPIPE such a write raises is blocked and taken back, so it
// stays an error of this pipe and never stops the batch (stop_signals.hpp:
// SIGPIPE stops it when its own output's reader is gone).
bool write_all(int fd, const std::string& text) {
  sigset_t pipe_signal;
  sigset_t before;
  sigemptyset(&pipe_signal);
  sigaddset(&pipe_signal, SIGPIPE);
  pthread_sigmask(SIG_BLOCK, &pipe_signal, &before);
  std::size_t done = 0;
  bool broken = false;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      broken = n < 0 && errno == EPIPE;
      break;
    }
    done += static_cast<std::size_t>(n);
  }
  if (broken && sigismember(&before, SIGPIPE) == 0) {
    const timespec now{0, 0};
    sigtimedwait(&pipe_signal, nullptr, &now);  // the one this write raised
  }
  pthread_sigmask(SIG_SETMASK, &before, nullptr);
  return done == text.size();
}

// The first whole line in `buffer`, taken out of it; nothing while there is none.
std::optional<std::string> take_line(std::string& buffer) {
  const auto nl = buffer.find('\n');
  if (nl == std::string::npos) return std::nullopt;
  std::string line = buffer.substr(0, nl);
  buffer.erase(0, nl + 1);
  return line;
}

// A line from `fd` (blocking), or nothing at its end.
std::optional<std::string> read_line(int fd, std::string& buffer) {
  for (;;) {
    if (auto line = take_line(buffer)) return line;
    char b[4096];
    const ssize_t n = ::read(fd, b, sizeof b);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return std::nullopt;
    buffer.append(b, static_cast<std::size_t>(n));
  }
}

// play()'s SetupError, as the line that tells the parent.
std::string error_line(const SetupError& e) {
  std::string text = e.what();
  for (char& c : text) c = c == '\n' ? ' ' : c;
  return "e " + text + "\n";
}

[[noreturn]] void worker_main(int in, int out, int index, const MatchJobs& jobs) {
  use_worker_rtdb_keys(index);  // its own RTDB keys: never another worker's, nor a robot's
  std::shared_ptr<void> held;
  if (jobs.enter) {
    try {
      held = jobs.enter(index);
    } catch (const SetupError& e) {
      write_all(out, error_line(e));
      std::fflush(nullptr);
      _exit(0);
    }
  }
  std::string buffer;
  while (const auto line = read_line(in, buffer)) {
    char* end = nullptr;
    const long number_l = std::strtol(line->c_str(), &end, 10);
    if (end == line->c_str() || *end != ' ') break;
    const char* seed_text = end + 1;
    const unsigned long long seed = std::strtoull(seed_text, &end, 10);
    if (end == seed_text) break;
    const int number = static_cast<int>(number_l);
    std::string reply;
    try {
      const std::string record = jobs.play(number, seed, [&](double s) {
        char p[64];
        std::snprintf(p, sizeof p, "p %llu %.3f\n", seed, s);
        write_all(out, p);
      });
      reply = "r " + record + "\n";
    } catch (const SetupError& e) {
      reply = error_line(e);
    }
    if (!write_all(out, reply)) break;
  }
  release_private_rtdb_keys();
  held.reset();
  std::fflush(nullptr);
  _exit(0);
}

Worker start(int index, const MatchJobs& jobs, const std::vector<Worker>& others) {
  int to[2], from[2];
  if (::pipe2(to, O_CLOEXEC) != 0 || ::pipe2(from, O_CLOEXEC) != 0) {
    throw SetupError(std::string("canhil match: cannot make a worker's pipes: ") + std::strerror(errno));
  }
  std::fflush(nullptr);  // nothing buffered is written twice
  const pid_t pid = ::fork();
  if (pid < 0) throw SetupError(std::string("canhil match: cannot start a worker: ") + std::strerror(errno));
  if (pid == 0) {
    for (const Worker& w : others) {
      if (w.to >= 0) ::close(w.to);
      if (w.from >= 0) ::close(w.from);
    }
    ::close(to[1]);
    ::close(from[0]);
    worker_main(to[0], from[1], index, jobs);
  }
  ::close(to[0]);
  ::close(from[1]);
  Worker w;
  w.pid = pid;
  w.to = to[1];
  w.from = from[0];
  return w;
}

std::string how_it_ended(int status) {
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    return std::string("its process was killed by signal ") + std::to_string(sig) + " (" + strsignal(sig) + ")";
  }
  return "its process ended with exit status " + std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) +
         " before the match did";
}

}  // namespace

void play_in_workers(const std::vector<std::uint64_t>& seeds, int workers, const MatchJobs& jobs,
                     const std::atomic<bool>& stop) {
  std::vector<Worker> pool;
  std::size_t next = 0;     // the next seed to hand out
  std::size_t emitted = 0;  // records passed to done()
  std::map<std::uint64_t, std::string> finished;
  std::map<std::uint64_t, int> number_of;
  for (std::size_t k = 0; k < seeds.size(); ++k) number_of[seeds[k]] = static_cast<int>(k + 1);
  std::string error;
  auto hand_out = [&](Worker& w) {
    if (w.to < 0) return;
    if (next < seeds.size() && !stop && error.empty()) {
      const std::uint64_t seed = seeds[next++];
      w.playing = seed;
      if (write_all(w.to, std::to_string(number_of[seed]) + " " + std::to_string(seed) + "\n")) return;
      w.playing.reset();
      --next;
    }
    ::close(w.to);  // nothing more: the worker ends
    w.to = -1;
  };
  const int count =
      static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(std::max(1, workers)), seeds.size()));
  for (int i = 0; i < count; ++i) {
    pool.push_back(start(i, jobs, pool));
    hand_out(pool.back());
  }
  bool told_to_stop = false;
  for (;;) {
    if (stop && !told_to_stop) {  // each worker stops its match now, as the batch's own process would
      for (const Worker& w : pool) {
        if (w.pid > 0) ::kill(w.pid, SIGTERM);
      }
      told_to_stop = true;
    }
    while (emitted < seeds.size() && finished.count(seeds[emitted]) != 0) jobs.done(finished[seeds[emitted++]]);
    std::vector<pollfd> fds;
    std::vector<std::size_t> which;
    for (std::size_t i = 0; i < pool.size(); ++i) {
      if (pool[i].from < 0) continue;
      fds.push_back({pool[i].from, POLLIN, 0});
      which.push_back(i);
    }
    if (fds.empty()) break;
    if (::poll(fds.data(), fds.size(), 200) < 0 && errno != EINTR) break;
    for (std::size_t f = 0; f < fds.size(); ++f) {
      if ((fds[f].revents & (POLLIN | POLLHUP | POLLERR)) == 0) continue;
      Worker& w = pool[which[f]];
      char b[65536];
      const ssize_t n = ::read(w.from, b, sizeof b);
      if (n < 0 && errno == EINTR) continue;
      if (n > 0) {
        w.buffer.append(b, static_cast<std::size_t>(n));
        while (const auto taken = take_line(w.buffer)) {
          const std::string& line = *taken;
          if (line.rfind("p ", 0) == 0) {
            char* end = nullptr;
            const unsigned long long seed = std::strtoull(line.c_str() + 2, &end, 10);
            const char* played = end;
            const double s = std::strtod(played, &end);
            if (end != played && jobs.progress) jobs.progress(seed, s);
          } else if (line.rfind("r ", 0) == 0 && w.playing) {
            finished[*w.playing] = line.substr(2);
            w.playing.reset();
            hand_out(w);
          } else if (line.rfind("e ", 0) == 0) {
            error = line.substr(2);
            w.playing.reset();
            hand_out(w);
          }
        }
        continue;
      }
      // The worker is gone: a match it was playing failed, and another worker takes the rest.
      ::close(w.from);
      w.from = -1;
      if (w.to >= 0) ::close(w.to);
      w.to = -1;
      int status = 0;
      ::waitpid(w.pid, &status, 0);
      w.pid = -1;
      if (w.playing) {
        finished[*w.playing] = jobs.failed(*w.playing, how_it_ended(status));
        w.playing.reset();
        if (next < seeds.size() && !stop && error.empty()) {
          pool.push_back(start(static_cast<int>(pool.size()), jobs, pool));
          hand_out(pool.back());
        }
      }
    }
  }
  for (Worker& w : pool) {
    if (w.to >= 0) ::close(w.to);
    if (w.from >= 0) ::close(w.from);
    if (w.pid > 0) ::waitpid(w.pid, nullptr, 0);
  }
  if (!error.empty()) {
    // What the other workers finished is still reported, in the order of the seeds.
    for (std::size_t k = emitted; k < seeds.size(); ++k) {
      if (const auto f = finished.find(seeds[k]); f != finished.end()) jobs.done(f->second);
    }
    throw SetupError(error);
  }
}

}  // namespace canhil::external
