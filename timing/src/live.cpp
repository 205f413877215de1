#include "canhil/timing/live.hpp"

#include "canhil/frames/wire.hpp"

namespace canhil::timing {

LiveBusStats::LiveBusStats(std::shared_ptr<const frames::MessageSet> set, std::uint32_t bit_rate, Nanos window)
    : set_(std::move(set)), bit_rate_(bit_rate), window_(window), window_end_(window) {
  for (const frames::MessageCodec& m : set_->codec().messages()) {
    const frames::FttInfo& ftt = set_->ftt(m);
    messages_.push_back(PerMessage{ftt.kind == frames::FttKind::kAsync ? Nanos{0} : ftt.period});
  }
}

void LiveBusStats::add(const frames::TimedFrame& f) {
  advance(f.time);
  ++frames_;
  if (f.frame.kind == frames::FrameKind::kError) {
    bits_ += frames::kErrorFrameBits;
    return;
  }
  bits_ += frames::frame_bits(f.frame);
  if (f.frame.kind != frames::FrameKind::kData) return;
  const frames::MessageCodec* m = set_->codec().find(f.frame.id, f.frame.extended);
  if (m == nullptr) return;
  PerMessage& p = messages_[static_cast<std::size_t>(m - set_->codec().messages().data())];
  if (p.nominal > Nanos{0} && p.last >= Nanos{0}) {
    const Nanos off = f.time - p.last - p.nominal;
    const Nanos dev = off < Nanos{0} ? -off : off;
    if (dev > p.worst) p.worst = dev;
  }
  p.last = f.time;
}

void LiveBusStats::advance(Nanos now) {
  while (now >= window_end_) {
    close_window();
    window_end_ += window_;
  }
}

void LiveBusStats::close_window() {
  load_ = static_cast<double>(bits_) / (static_cast<double>(bit_rate_) * to_seconds(window_));
  bits_ = 0;
  jitter_.clear();
  const auto all = set_->codec().messages();
  for (std::size_t i = 0; i < messages_.size(); ++i) {
    PerMessage& p = messages_[i];
    if (p.worst >= Nanos{0}) jitter_.emplace_back(std::string(all[i].name()), to_ms(p.worst));
    p.worst = Nanos{-1};
  }
}

}  // namespace canhil::timing
