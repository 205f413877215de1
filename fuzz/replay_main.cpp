// Corpus replay for compilers without libFuzzer (g++): runs the target on
// every file of the given directories, then on seeded random mutations of
// them, so the fuzz targets build and run in every configuration.
//   replay [--mutations N] DIR...
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

int main(int argc, char** argv) {
  long mutations = 20000;
  std::vector<std::vector<std::uint8_t>> inputs;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--mutations" && i + 1 < argc) {
      mutations = std::stol(argv[++i]);
      continue;
    }
    for (const auto& entry : std::filesystem::directory_iterator(arg)) {
      std::ifstream in(entry.path(), std::ios::binary);
      inputs.emplace_back(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
  }
  if (inputs.empty()) {
    std::fprintf(stderr, "replay: no corpus files given\n");
    return 2;
  }
  for (const auto& in : inputs) LLVMFuzzerTestOneInput(in.data(), in.size());
  std::mt19937 rng(12345);
  for (long k = 0; k < mutations; ++k) {
    std::vector<std::uint8_t> m = inputs[rng() % inputs.size()];
    const auto edits = 1 + rng() % 8;
    for (std::uint32_t e = 0; e < edits; ++e) {
      const auto op = rng() % 3;
      if (op == 0 && !m.empty()) m[rng() % m.size()] = static_cast<std::uint8_t>(rng());
      if (op == 1)
        m.insert(m.begin() + static_cast<long>(m.empty() ? 0 : rng() % m.size()), static_cast<std::uint8_t>(rng()));
      if (op == 2 && !m.empty()) m.erase(m.begin() + static_cast<long>(rng() % m.size()));
    }
    LLVMFuzzerTestOneInput(m.data(), m.size());
  }
  std::printf("replay: %zu corpus inputs and %ld mutations ran\n", inputs.size(), mutations);
  return 0;
}
