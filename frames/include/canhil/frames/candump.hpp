// canhil/frames/candump.hpp — can-utils' text formats, both ways.
//
//   compact:  123#1122334455667788   12345678#11.22   123#R   123#R3
//             20000004#0000000000000000 (error frame: 8 hex digits with bit 29 set)
//             123#1122334455667788_C  (classic frame, raw DLC 9..15)
//   log:      (1700000000.000100) vcan0 131#F401000000000000
//
// Identifiers with 3 hex digits are standard, with 8 extended (or error, when
// bit 29 — CAN_ERR_FLAG — is set). Data bytes are two hex digits each and may be
// separated by '.'. These are the rules of can-utils' lib.c; canplayer,
// candump -r and log2asc read what format_* writes. CAN FD frames (`##`) are
// not supported and are reported as such.
//
// Pure functions: no I/O, no globals; thread-safe.
#pragma once

#include <string>
#include <string_view>

#include "canhil/frames/frame.hpp"

namespace canhil::frames {

/// Parses the compact form. On failure returns false and, if `error` is not
/// null, sets it to a sentence saying what is wrong; `out` is then unspecified.
bool parse_compact(std::string_view text, CanFrame& out, std::string* error = nullptr);

/// Longest compact text: 8 id digits, '#', 16 data digits, "_X", NUL.
inline constexpr std::size_t kCompactMaxChars = 8 + 1 + 16 + 2 + 1;

/// Writes the compact form into `buf` (NUL-terminated); returns its length.
/// Never allocates.
std::size_t format_compact(const CanFrame& frame, char (&buf)[kCompactMaxChars]);
std::string format_compact(const CanFrame& frame);

struct LogEntry {
  Nanos time{0};  ///< microsecond resolution in the text format
  std::string iface;
  CanFrame frame;
};

/// Parses one line of candump's log format (`-l` / `-L`). Trailing white space
/// and a trailing carriage return are accepted.
bool parse_log_line(std::string_view line, LogEntry& out, std::string* error = nullptr);

/// `(SSSSSSSSSS.UUUUUU) IFACE FRAME`, without a newline.
std::string format_log_line(Nanos time, std::string_view iface, const CanFrame& frame);

}  // namespace canhil::frames
