#include "canhil/physics/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "canhil/base/xml_text.hpp"

namespace canhil::physics {
namespace {

constexpr double kWidth = 760;
constexpr double kHeight = 380;
constexpr double kLeft = 70;
constexpr double kRight = 20;
constexpr double kTop = 40;
constexpr double kBottom = 50;
const char* const kColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd",
                                "#8c564b", "#e377c2", "#17becf", "#7f7f7f", "#bcbd22"};

double nice_step(double span) {
  const double raw = span / 6;
  const double mag = std::pow(10, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (raw <= m * mag) return m * mag;
  }
  return 10 * mag;
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", std::fabs(v) < 1e-12 ? 0.0 : v);
  return buf;
}

void plot_one(std::ostringstream& os, const Plot& p, double y0) {
  double xmin = std::numeric_limits<double>::infinity();
  double xmax = -xmin;
  double ymin = xmin;
  double ymax = -xmin;
  for (const auto& s : p.series) {
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      xmin = std::min(xmin, s.x[i]);
      xmax = std::max(xmax, s.x[i]);
      ymin = std::min(ymin, s.y[i]);
      ymax = std::max(ymax, s.y[i]);
    }
  }
  if (!std::isfinite(xmin)) {
    xmin = 0, xmax = 1, ymin = 0, ymax = 1;
  }
  if (xmax - xmin < 1e-12) xmax = xmin + 1;
  if (ymax - ymin < 1e-12) {
    ymin -= 0.5;
    ymax += 0.5;
  }
  const double pad = (ymax - ymin) * 0.05;
  ymin -= pad;
  ymax += pad;
  const double pw = kWidth - kLeft - kRight;
  const double ph = kHeight - kTop - kBottom;
  auto X = [&](double x) { return kLeft + (x - xmin) / (xmax - xmin) * pw; };
  auto Y = [&](double y) { return y0 + kTop + ph - (y - ymin) / (ymax - ymin) * ph; };
  os << "<text x='" << kWidth / 2 << "' y='" << y0 + 22 << "' text-anchor='middle' font-size='15'>" << xml_text(p.title)
     << "</text>\n";
  os << "<rect x='" << kLeft << "' y='" << y0 + kTop << "' width='" << pw << "' height='" << ph
     << "' fill='none' stroke='#444'/>\n";
  const double xs = nice_step(xmax - xmin);
  const auto x_last = static_cast<long>(std::floor((xmax + 1e-9) / xs));
  for (auto i = static_cast<long>(std::ceil(xmin / xs)); i <= x_last; ++i) {
    const double t = static_cast<double>(i) * xs;
    os << "<line x1='" << X(t) << "' y1='" << y0 + kTop << "' x2='" << X(t) << "' y2='" << y0 + kTop + ph
       << "' stroke='#eee'/><text x='" << X(t) << "' y='" << y0 + kTop + ph + 16
       << "' text-anchor='middle' font-size='11'>" << num(t) << "</text>\n";
  }
  const double ys = nice_step(ymax - ymin);
  const auto y_last = static_cast<long>(std::floor((ymax + 1e-9) / ys));
  for (auto i = static_cast<long>(std::ceil(ymin / ys)); i <= y_last; ++i) {
    const double t = static_cast<double>(i) * ys;
    os << "<line x1='" << kLeft << "' y1='" << Y(t) << "' x2='" << kLeft + pw << "' y2='" << Y(t)
       << "' stroke='#eee'/><text x='" << kLeft - 6 << "' y='" << Y(t) + 4 << "' text-anchor='end' font-size='11'>"
       << num(t) << "</text>\n";
  }
  os << "<text x='" << kLeft + pw / 2 << "' y='" << y0 + kHeight - 10 << "' text-anchor='middle' font-size='12'>"
     << xml_text(p.x_label) << "</text>\n";
  os << "<text transform='translate(16," << y0 + kTop + ph / 2 << ") rotate(-90)' text-anchor='middle' font-size='12'>"
     << xml_text(p.y_label) << "</text>\n";
  for (std::size_t k = 0; k < p.series.size(); ++k) {
    const auto& s = p.series[k];
    const char* colour = kColours[k % std::size(kColours)];
    os << "<polyline fill='none' stroke='" << colour << "' stroke-width='1.5' points='";
    // At most ~2000 points per series keeps files small.
    const std::size_t stride = std::max<std::size_t>(1, s.x.size() / 2000);
    for (std::size_t i = 0; i < s.x.size(); i += stride) {
      if (std::isfinite(s.x[i]) && std::isfinite(s.y[i])) os << X(s.x[i]) << ',' << Y(s.y[i]) << ' ';
    }
    os << "'/>\n";
    os << "<rect x='" << kLeft + pw - 190 << "' y='" << y0 + kTop + 8 + 16 * static_cast<double>(k)
       << "' width='10' height='10' fill='" << colour << "'/><text x='" << kLeft + pw - 175 << "' y='"
       << y0 + kTop + 17 + 16 * static_cast<double>(k) << "' font-size='11'>" << xml_text(s.name) << "</text>\n";
  }
}

}  // namespace

std::string svg_plots(const std::vector<Plot>& plots) {
  std::ostringstream os;
  const double total = kHeight * static_cast<double>(std::max<std::size_t>(1, plots.size()));
  os << "<svg xmlns='http://www.w3.org/2000/svg' width='" << kWidth << "' height='" << total
     << "' font-family='sans-serif'>\n<rect width='100%' height='100%' fill='white'/>\n";
  for (std::size_t i = 0; i < plots.size(); ++i) plot_one(os, plots[i], kHeight * static_cast<double>(i));
  os << "</svg>\n";
  return os.str();
}

}  // namespace canhil::physics
