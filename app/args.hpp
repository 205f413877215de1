// app/args.hpp — a small, strict command-line parser for canhil's subcommands.
#pragma once

#include <algorithm>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "canhil/base/setup_error.hpp"
#include "canhil/frames/ftt.hpp"

namespace canhil::app {

/// A command-line mistake; main prints it with the command's usage and exits 2.
class UsageError : public SetupError {
 public:
  using SetupError::SetupError;
};

class Args {
 public:
  /// The words of the command line; those after a lone "--" are kept apart,
  /// untouched (a command to run: `canhil bus exec -- candump -l vcan0`).
  Args(std::vector<std::string> words) : words_(std::move(words)) {
    for (std::size_t i = 0; i < words_.size(); ++i) {
      if (words_[i] == "--") {
        after_dashes_.assign(words_.begin() + static_cast<long>(i) + 1, words_.end());
        words_.resize(i);
        has_dashes_ = true;
        break;
      }
    }
  }

  /// The word after `word` (a subcommand: "up" of `canhil bus up`), or "".
  /// Whether `--name` (or `--name=...`) is on the command line, not yet taken.
  bool given(const std::string& name) const {
    return std::any_of(words_.begin(), words_.end(),
                       [&](const std::string& w) { return w == name || w.rfind(name + "=", 0) == 0; });
  }
  std::string word_after(const std::string& word) const {
    for (std::size_t i = 0; i + 1 < words_.size(); ++i) {
      if (words_[i] == word) return words_[i + 1];
    }
    return "";
  }

  /// The words after "--", and whether there was one.
  const std::vector<std::string>& after_dashes() const { return after_dashes_; }
  bool has_dashes() const { return has_dashes_; }

  /// Removes `--name VALUE` (or `--name=VALUE`) and returns VALUE.
  std::optional<std::string> option(const std::string& name) {
    for (std::size_t i = 0; i < words_.size(); ++i) {
      if (words_[i] == name) {
        if (i + 1 >= words_.size()) throw UsageError(name + " needs a value");
        std::string v = words_[i + 1];
        words_.erase(words_.begin() + static_cast<long>(i), words_.begin() + static_cast<long>(i) + 2);
        return v;
      }
      if (words_[i].rfind(name + "=", 0) == 0) {
        std::string v = words_[i].substr(name.size() + 1);
        words_.erase(words_.begin() + static_cast<long>(i));
        return v;
      }
    }
    return std::nullopt;
  }
  /// Removes `--name` and says whether it was there.
  bool flag(const std::string& name) {
    for (std::size_t i = 0; i < words_.size(); ++i) {
      if (words_[i] == name) {
        words_.erase(words_.begin() + static_cast<long>(i));
        return true;
      }
    }
    return false;
  }
  /// The first word that is not an option (the subcommand), or "".
  std::string command() const {
    for (const auto& w : words_) {
      if (w.empty() || w[0] != '-') return w;
    }
    return "";
  }
  /// What is left, after options were taken; unknown `--x` words are an error.
  std::vector<std::string> positionals() const {
    for (const auto& w : words_) {
      if (w.size() > 1 && w[0] == '-' && w != "-") throw UsageError("unknown option " + w);
    }
    return words_;
  }

 private:
  std::vector<std::string> words_;
  std::vector<std::string> after_dashes_;
  bool has_dashes_ = false;
};

/// Removes `--name VALUE` and returns VALUE as a number; nothing when absent.
inline std::optional<double> optional_number(Args& args, const std::string& name) {
  const auto v = args.option(name);
  if (!v) return std::nullopt;
  try {
    std::size_t used = 0;
    const double d = std::stod(*v, &used);
    if (used != v->size()) throw std::invalid_argument(*v);
    return d;
  } catch (const std::exception&) {
    throw UsageError(name + " takes a number, got \"" + *v + "\"");
  }
}

/// Removes `--name VALUE` and returns VALUE as a number, or `fallback` when absent.
inline double number_option(Args& args, const std::string& name, double fallback) {
  return optional_number(args, name).value_or(fallback);
}

/// Removes `--seed S` and returns S (a whole number, 0 or more); nothing when absent.
inline std::optional<std::uint64_t> seed_option(Args& args) {
  const auto text = args.option("--seed");
  if (!text) return std::nullopt;
  std::size_t used = 0;
  std::uint64_t seed = 0;
  try {
    seed = std::stoull(*text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text->size() || text->empty() || (*text)[0] == '-') {
    throw UsageError("--seed takes a whole number, 0 or more, got '" + *text + "'");
  }
  return seed;
}

/// Removes `--stamps start|end` (what a trace's time stamps mark: a frame's
/// first bit, as on vcan, or its end of frame, as on a real can0 or canhil's
/// timed wire); start when absent.
inline frames::StampAt stamps_option(Args& args) {
  const auto v = args.option("--stamps");
  if (!v || *v == "start") return frames::StampAt::kStartOfFrame;
  if (*v == "end") return frames::StampAt::kEndOfFrame;
  throw UsageError(
      "--stamps takes start (a frame's first bit: vcan) or end (its end of frame: a real can0, canhil's "
      "timed wire), got '" +
      *v + "'");
}

}  // namespace canhil::app
