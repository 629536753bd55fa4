// The driver that runs a fuzz target without libFuzzer (gcc, the main build): every file
// of the corpus and regression folders given, then random mutations of them for a few
// seconds from a fixed seed, so that ctest exercises each target on every test run.
// The same target source built with clang's -fsanitize=fuzzer is the real fuzzer
// (bench/fuzz.sh, docs/fuzzing.md).
//
//   fuzz_<target>_replay [--seconds S] [--seed N] [--max-len BYTES] FILE_OR_DIR...
//
// Exit status 0 when every input ran (a crash ends the process: that is the failure).
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

using Bytes = std::vector<std::uint8_t>;

struct Options {
  double seconds = 3.0;
  std::uint64_t seed = 1;
  std::size_t max_len = 16384;
  std::vector<std::filesystem::path> inputs;
};

Bytes readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// Every regular file under the paths, in a stable order.
std::vector<std::filesystem::path> inputFiles(const std::vector<std::filesystem::path>& roots) {
  std::vector<std::filesystem::path> files;
  for (const auto& root : roots) {
    if (std::filesystem::is_regular_file(root)) {
      files.push_back(root);
    } else if (std::filesystem::is_directory(root)) {
      for (const auto& entry : std::filesystem::recursive_directory_iterator(root))
        if (entry.is_regular_file()) files.push_back(entry.path());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

void run(const Bytes& input) { LLVMFuzzerTestOneInput(input.data(), input.size()); }

// One random edit of `bytes`, the kinds libFuzzer starts with: flip a bit, set a byte
// to a random or boundary value, insert or erase a run, copy a run inside, splice
// another input's run in.
void mutate(Bytes& bytes, const Bytes& other, std::mt19937_64& rng, std::size_t max_len) {
  auto pick = [&](std::size_t n) { return n == 0 ? std::size_t{0} : static_cast<std::size_t>(rng() % n); };
  static constexpr std::uint8_t kBoundaries[] = {0, 1, 0x7f, 0x80, 0xff, '0', '9', '"', '<', '>', '(', ')', '[', ']'};
  switch (rng() % 7) {
    case 0:
      if (!bytes.empty()) bytes[pick(bytes.size())] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
      break;
    case 1:
      if (!bytes.empty()) bytes[pick(bytes.size())] = static_cast<std::uint8_t>(rng());
      break;
    case 2:
      if (!bytes.empty()) bytes[pick(bytes.size())] = kBoundaries[pick(std::size(kBoundaries))];
      break;
    case 3: {  // insert random bytes
      const std::size_t at = pick(bytes.size() + 1), n = 1 + pick(8);
      Bytes run(n);
      for (auto& b : run) b = static_cast<std::uint8_t>(rng());
      bytes.insert(bytes.begin() + static_cast<std::ptrdiff_t>(at), run.begin(), run.end());
      break;
    }
    case 4: {  // erase a run
      if (bytes.empty()) break;
      const std::size_t at = pick(bytes.size()), n = 1 + pick(std::min<std::size_t>(16, bytes.size() - at));
      bytes.erase(bytes.begin() + static_cast<std::ptrdiff_t>(at), bytes.begin() + static_cast<std::ptrdiff_t>(at + n));
      break;
    }
    case 5: {  // duplicate a run of itself
      if (bytes.empty()) break;
      const std::size_t from = pick(bytes.size()), n = 1 + pick(std::min<std::size_t>(64, bytes.size() - from));
      const Bytes run(bytes.begin() + static_cast<std::ptrdiff_t>(from), bytes.begin() + static_cast<std::ptrdiff_t>(from + n));
      bytes.insert(bytes.begin() + static_cast<std::ptrdiff_t>(pick(bytes.size() + 1)), run.begin(), run.end());
      break;
    }
    default: {  // splice a run of another input in
      if (other.empty()) break;
      const std::size_t from = pick(other.size()), n = 1 + pick(std::min<std::size_t>(64, other.size() - from));
      bytes.insert(bytes.begin() + static_cast<std::ptrdiff_t>(pick(bytes.size() + 1)),
                   other.begin() + static_cast<std::ptrdiff_t>(from), other.begin() + static_cast<std::ptrdiff_t>(from + n));
      break;
    }
  }
  if (bytes.size() > max_len) bytes.resize(max_len);
}

bool parseOptions(int argc, char** argv, Options& options) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    if (arg == "--seconds" || arg == "--seed" || arg == "--max-len") {
      const char* v = value();
      if (!v) {
        std::fprintf(stderr, "%s needs a value\n", arg.c_str());
        return false;
      }
      if (arg == "--seconds") options.seconds = std::atof(v);
      if (arg == "--seed") options.seed = std::strtoull(v, nullptr, 10);
      if (arg == "--max-len") options.max_len = std::strtoull(v, nullptr, 10);
    } else {
      options.inputs.emplace_back(arg);
    }
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  if (!parseOptions(argc, argv, options)) return 2;
  const auto files = inputFiles(options.inputs);
  std::vector<Bytes> seeds;
  for (const auto& file : files) {
    seeds.push_back(readFile(file));
    run(seeds.back());
  }
  if (seeds.empty()) seeds.emplace_back();
  std::printf("replayed %zu files\n", files.size());

  std::mt19937_64 rng(options.seed);
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(options.seconds);
  std::uint64_t runs = 0;
  while (std::chrono::steady_clock::now() < end) {
    Bytes input = seeds[rng() % seeds.size()];
    const Bytes& other = seeds[rng() % seeds.size()];
    const int edits = 1 + static_cast<int>(rng() % 4);
    for (int k = 0; k < edits; ++k) mutate(input, other, rng, options.max_len);
    run(input);
    ++runs;
  }
  std::printf("ran %llu mutated inputs in %.1f s (seed %llu)\n", static_cast<unsigned long long>(runs),
              options.seconds, static_cast<unsigned long long>(options.seed));
  return 0;
}
