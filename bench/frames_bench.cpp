// frames_bench — encode + decode time per frame over the whole message set.
// Target (issue 2): at most 50 ns per frame, no heap allocation per frame.
// Counters: time_per_frame (encode+decode of one frame, e.g. "12.3n" = 12.3 ns), allocs_per_frame
// (global operator new calls during the timed loop, per frame).
#include <benchmark/benchmark.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "canhil/frames/candump.hpp"
#include "canhil/frames/messages.hpp"
#include "canhil/frames/wire.hpp"

namespace {
std::atomic<std::uint64_t> g_allocations{0};
}  // namespace

void* operator new(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace {

using namespace canhil::frames;

const Codec& shipped() {
  static const Codec codec(load_dbc(CANHIL_BENCH_DBC));
  return codec;
}

void report(benchmark::State& state, std::uint64_t frames, std::uint64_t allocs) {
  state.SetItemsProcessed(static_cast<std::int64_t>(frames));
  // Seconds per frame, printed with an SI prefix ("12.3n" = 12.3 ns).
  state.counters["time_per_frame"] =
      benchmark::Counter(static_cast<double>(frames), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["allocs_per_frame"] = static_cast<double>(allocs) / static_cast<double>(frames);
}

// Generic path: physical values in, frame out, physical values back, for every
// message of the set in turn (16 messages, 42 signals).
void BM_EncodeDecodeWholeSet(benchmark::State& state) {
  const Codec& codec = shipped();
  const auto messages = codec.messages();
  std::array<double, kMaxSignals> in{};
  std::array<double, kMaxSignals> out{};
  CanFrame frame;
  std::uint64_t frames = 0;
  const std::uint64_t allocs_before = g_allocations.load();
  for (auto _ : state) {
    for (const MessageCodec& m : messages) {
      in[0] += 1e-3;
      m.encode(std::span<const double>(in.data(), m.signal_count()), frame);
      benchmark::DoNotOptimize(frame);
      const DecodeResult r = m.decode(frame, out);
      benchmark::DoNotOptimize(r);
      benchmark::DoNotOptimize(out);
    }
    frames += messages.size();
  }
  report(state, frames, g_allocations.load() - allocs_before);
}
BENCHMARK(BM_EncodeDecodeWholeSet);

// Receive path as a node sees it: id lookup + decode of every message.
void BM_LookupAndDecodeWholeSet(benchmark::State& state) {
  const Codec& codec = shipped();
  std::vector<CanFrame> frames_in;
  for (const MessageCodec& m : codec.messages()) {
    CanFrame f;
    m.encode(m.initial_values(), f);
    frames_in.push_back(f);
  }
  std::array<double, kMaxSignals> out{};
  std::uint64_t frames = 0;
  const std::uint64_t allocs_before = g_allocations.load();
  for (auto _ : state) {
    for (const CanFrame& f : frames_in) {
      const DecodeResult r = codec.decode(f, out);
      benchmark::DoNotOptimize(r);
      benchmark::DoNotOptimize(out);
    }
    frames += frames_in.size();
  }
  report(state, frames, g_allocations.load() - allocs_before);
}
BENCHMARK(BM_LookupAndDecodeWholeSet);

// Typed path: the structs the nodes use.
void BM_TypedEncodeDecode(benchmark::State& state) {
  static const auto set = MessageSet::load(CANHIL_BENCH_DBC);
  M6_1 v{0.5, 0.0};
  M6_1 back;
  M3 e{123456, 360, 0, 0};
  M3 e_back;
  std::uint64_t frames = 0;
  const std::uint64_t allocs_before = g_allocations.load();
  for (auto _ : state) {
    v.vx += 1e-3;
    set->m6_1.decode(set->m6_1.encode(v), back);
    ++e.seq;
    set->m3[0].decode(set->m3[0].encode(e), e_back);
    benchmark::DoNotOptimize(back);
    benchmark::DoNotOptimize(e_back);
    frames += 2;
  }
  report(state, frames, g_allocations.load() - allocs_before);
}
BENCHMARK(BM_TypedEncodeDecode);

// candump compact text, both ways (traces and the CLI).
void BM_CompactFormatParse(benchmark::State& state) {
  CanFrame f = make_data_frame(0x131, {0xF4, 0x01, 0, 0, 0, 0, 0, 0});
  CanFrame back;
  char buf[kCompactMaxChars];
  std::uint64_t frames = 0;
  for (auto _ : state) {
    ++f.data[2];
    const std::size_t n = format_compact(f, buf);
    parse_compact(std::string_view(buf, n), back);
    benchmark::DoNotOptimize(back);
    ++frames;
  }
  report(state, frames, 0);
}
BENCHMARK(BM_CompactFormatParse);

// A classic frame's exact bits (stuffing over its bit stream with CRC-15):
// every frame on a timed wire is counted once.
void BM_CountClassicBits(benchmark::State& state) {
  WireFrame f;
  f.id = 0x131;
  f.len = 8;
  std::uint64_t x = 0x9E3779B97F4A7C15ull, frames = 0, bits = 0;
  for (auto _ : state) {
    x = x * 6364136223846793005ull + 1442695040888963407ull;
    for (int i = 0; i < 8; ++i) f.data[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(x >> (8 * i));
    bits += count_bits(f).total();
    ++frames;
  }
  benchmark::DoNotOptimize(bits);
  report(state, frames, 0);
}
BENCHMARK(BM_CountClassicBits);

}  // namespace

BENCHMARK_MAIN();
