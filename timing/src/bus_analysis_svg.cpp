// The analysis of a message set as one SVG picture.
#include <algorithm>
#include <cstdio>
#include <sstream>
#include <string>

#include "canhil/base/xml_text.hpp"
#include "canhil/timing/bus_analysis.hpp"

namespace canhil::timing {
namespace {

constexpr double kLeft = 150;   // room for the row labels
constexpr double kWidth = 900;  // the time axis
constexpr double kRow = 26;
constexpr double kTop = 50;

struct Svg {
  std::ostringstream os;
  void rect(double x, double y, double w, double h, const char* fill, const char* extra = "",
            const std::string& title = "") {
    char b[256];
    std::snprintf(b, sizeof b, "<rect x=\"%.2f\" y=\"%.2f\" width=\"%.2f\" height=\"%.2f\" fill=\"%s\" %s", x, y,
                  std::max(w, 0.5), h, fill, extra);
    os << b;
    if (title.empty()) {
      os << "/>\n";
    } else {
      os << "><title>" << xml_text(title) << "</title></rect>\n";  // the frame's name where the picture is hovered
    }
  }
  void text(double x, double y, const std::string& t, const char* extra = "") {
    char b[128];
    std::snprintf(b, sizeof b, "<text x=\"%.2f\" y=\"%.2f\" font-size=\"12\" %s>", x, y, extra);
    os << b << xml_text(t) << "</text>\n";
  }
};

std::string ms_text(Nanos t) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g ms", static_cast<double>(t.count()) / 1e6);
  return b;
}

void ftt_picture(Svg& s, const BusAnalysis& a, double& height) {
  const Nanos ec = a.config.ftt.elementary_cycle;
  const double scale = kWidth / static_cast<double>(ec.count());
  auto x = [&](Nanos t) { return kLeft + static_cast<double>(t.count()) * scale; };
  Nanos tm_wire{0};
  for (const FrameRow& f : a.frames) {
    if (f.kind == frames::FttKind::kTrigger) tm_wire = f.time.worst;
  }
  constexpr std::size_t kMostRows = 60;
  const std::size_t rows = std::min(a.sync.ecs.size(), kMostRows);
  s.text(kLeft, 20,
         "One schedule cycle, " + std::to_string(a.sync.cycle_ecs) + " ECs of " + ms_text(ec) +
             (a.sync.cycle_ecs > rows ? " (the first " + std::to_string(rows) + " drawn)" : "") +
             ": TM (black), asynchronous window (blue), synchronous window (orange), frames as bars",
         "font-weight=\"bold\"");
  for (std::size_t r = 0; r < rows; ++r) {
    const EcLoad& e = a.sync.ecs[r];
    const double y = kTop + static_cast<double>(r) * kRow;
    const bool worst = e.ec == a.sync.worst_ec;
    s.text(8, y + 16, "EC " + std::to_string(e.ec) + (worst ? "  worst" : ""), worst ? "fill=\"#c00\"" : "");
    const Nanos sync_start = ec - e.window;
    s.rect(x(Nanos{0}), y + 2, x(tm_wire) - kLeft, kRow - 6, "#222");
    s.rect(x(tm_wire), y + 2, x(sync_start) - x(tm_wire), kRow - 6, "#dbe8f7");
    s.rect(x(sync_start), y + 2, x(ec) - x(sync_start), kRow - 6, "#fde3c4");
    // The synchronous frames in arbitration order from the window's start.
    Nanos at = sync_start;
    for (const SyncBound& m : a.sync.messages) {
      if (((e.bitmap >> m.index) & 1u) == 0) continue;
      s.rect(x(at), y + 5, x(at + m.wire) - x(at) - 0.5, kRow - 12, "#e07b00", "stroke=\"#fff\" stroke-width=\"0.5\"",
             m.name);
      at += m.wire;
    }
    if (worst) {
      // Every sporadic frame at once, from the window's opening.
      Nanos t = tm_wire;
      for (const AsyncBound& m : a.async.messages) {
        s.rect(x(t), y + 5, x(t + m.wire) - x(t) - 0.5, kRow - 12, "#3a78c2", "stroke=\"#fff\" stroke-width=\"0.5\"",
               m.name + " (worst case: every sporadic frame at once)");
        t += m.wire;
      }
      s.rect(kLeft - 2, y, kWidth + 4, kRow - 2, "none", "stroke=\"#c00\" stroke-width=\"2\"");
    }
  }
  // The longest synchronous window allowed, as a line over every row.
  const double lsw = x(ec - a.sync.allowed_window);
  const double bottom = kTop + static_cast<double>(rows) * kRow;
  char b[200];
  std::snprintf(b, sizeof b,
                "<line x1=\"%.2f\" y1=\"%.2f\" x2=\"%.2f\" y2=\"%.2f\" stroke=\"#c00\" stroke-dasharray=\"4 3\"/>\n",
                lsw, kTop - 4, lsw, bottom);
  s.os << b;
  s.text(lsw + 3, kTop - 8, "longest synchronous window allowed", "fill=\"#c00\"");
  s.text(kLeft, bottom + 18, "0");
  s.text(kLeft + kWidth - 40, bottom + 18, ms_text(ec));
  height = bottom + 30;
}

void native_picture(Svg& s, const BusAnalysis& a, double& height) {
  Nanos longest{1};
  for (const ResponseBound& m : a.native.messages) {
    longest = std::max({longest, m.deadline, m.worst_response == kNever ? m.deadline : m.worst_response});
  }
  const double scale = kWidth / static_cast<double>(longest.count());
  s.text(kLeft, 20, "Worst-case response (bar) against the deadline (red line), longest " + ms_text(longest),
         "font-weight=\"bold\"");
  double y = kTop;
  for (const ResponseBound& m : a.native.messages) {
    s.text(8, y + 16, m.name);
    const bool unbounded = m.worst_response == kNever;
    const double w = unbounded ? kWidth : static_cast<double>(m.worst_response.count()) * scale;
    s.rect(kLeft, y + 5, w, kRow - 12, m.schedulable ? "#3a78c2" : "#c00");
    const double d = kLeft + static_cast<double>(m.deadline.count()) * scale;
    char b[200];
    std::snprintf(b, sizeof b,
                  "<line x1=\"%.2f\" y1=\"%.2f\" x2=\"%.2f\" y2=\"%.2f\" stroke=\"#c00\" stroke-width=\"2\"/>\n", d,
                  y + 1, d, y + kRow - 3);
    s.os << b;
    y += kRow;
  }
  height = y + 20;
}

}  // namespace

std::string format_analysis_svg(const BusAnalysis& a) {
  Svg body;
  double height = 0;
  if (a.ftt) {
    ftt_picture(body, a, height);
  } else {
    native_picture(body, a, height);
  }
  std::ostringstream os;
  char b[200];
  std::snprintf(
      b, sizeof b,
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" font-family=\"sans-serif\">\n",
      kLeft + kWidth + 20, height);
  os << b << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n" << body.os.str() << "</svg>\n";
  return os.str();
}

}  // namespace canhil::timing
