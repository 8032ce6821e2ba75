// A main for the fuzz targets without libFuzzer (GCC, the CTests fuzz_*): every file of the seed
// corpus, then a fixed series of mutations of them from a seeded generator, so that a CTest run
// replays every crash kept in the corpus and tries the same few thousand variants each time.
//   fuzz_<name> CORPUS_DIR [MUTATIONS [SECONDS]]   stops after MUTATIONS or SECONDS, whichever
//   comes first. A finding ends the program (sanitizer report, uncaught exception, broken
//   promise), which first writes the input to ./crash-input (to replay: fuzz_<name> DIR with it).
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);
// In the sanitizer runtimes (null without them): runs `callback` before a report ends the program.
extern "C" __attribute__((weak)) void __sanitizer_set_death_callback(void (*callback)());

namespace {

using Bytes = std::vector<std::uint8_t>;

/// splitmix64: the same draws on every platform.
class Random {
 public:
  explicit Random(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, n), n > 0.
  std::size_t below(std::size_t n) { return static_cast<std::size_t>(next() % n); }

 private:
  std::uint64_t state_;
};

/// Bytes a parser treats specially: digits, signs, separators, brackets, quotes, extremes.
constexpr char kInteresting[] = "0123456789-+.,:;e[]{}\"'#\n\r\t \\/*&!|%@xnN";

/// One edit of `b` at a random place: flip a bit, set a byte, insert or erase bytes, copy a
/// piece elsewhere, or truncate.
void mutateOnce(Bytes& b, Random& rng) {
  const std::size_t n = b.size();
  const std::size_t at = n == 0 ? 0 : rng.below(n);
  switch (rng.below(7)) {
    case 0:
      if (n) b[at] ^= static_cast<std::uint8_t>(1u << rng.below(8));
      break;
    case 1:
      if (n) b[at] = static_cast<std::uint8_t>(rng.next());
      break;
    case 2:
      b.insert(b.begin() + static_cast<std::ptrdiff_t>(at),
               static_cast<std::uint8_t>(kInteresting[rng.below(sizeof kInteresting - 1)]));
      break;
    case 3:
      if (n)
        b.erase(b.begin() + static_cast<std::ptrdiff_t>(at),
                b.begin() + static_cast<std::ptrdiff_t>(
                                at + 1 + rng.below(std::min<std::size_t>(n - at, 16))));
      break;
    case 4: {  // a piece of up to 32 bytes copied over another place
      if (!n) break;
      const std::size_t from = rng.below(n),
                        len = 1 + rng.below(std::min<std::size_t>(n - from, 32));
      const Bytes piece(b.begin() + static_cast<std::ptrdiff_t>(from),
                        b.begin() + static_cast<std::ptrdiff_t>(from + len));
      b.insert(b.begin() + static_cast<std::ptrdiff_t>(at), piece.begin(), piece.end());
      break;
    }
    case 5:
      if (n) b[at] = static_cast<std::uint8_t>(kInteresting[rng.below(sizeof kInteresting - 1)]);
      break;
    default:
      b.resize(at);
      break;
  }
}

// The input being run, written to ./crash-input when the program dies on it.
const Bytes* current = nullptr;

void saveCurrent() {
  if (!current) return;
  const int fd = ::open("crash-input", O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) return;
  const bool saved = ::write(fd, current->data(), current->size()) >= 0;
  ::close(fd);
  current = nullptr;
  const char note[] = "fuzz: the input is in ./crash-input\n";
  if (saved && ::write(STDERR_FILENO, note, sizeof note - 1) < 0) return;
}

extern "C" void onDeath() { saveCurrent(); }
extern "C" void onSignal(int signal) {
  saveCurrent();
  std::signal(signal, SIG_DFL);
  std::raise(signal);
}

Bytes readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void run(const Bytes& input) {
  current = &input;
  LLVMFuzzerTestOneInput(input.data(), input.size());
  current = nullptr;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || argc > 4) {
    std::fprintf(stderr, "usage: %s CORPUS_DIR [MUTATIONS [SECONDS]]\n", argv[0]);
    return 2;
  }
  std::signal(SIGABRT, onSignal);  // broken promises, uncaught exceptions
  std::signal(SIGSEGV, onSignal);
  if (__sanitizer_set_death_callback) __sanitizer_set_death_callback(onDeath);  // their reports
  const long mutations = argc > 2 ? std::atol(argv[2]) : 4000;
  const double seconds = argc > 3 ? std::atof(argv[3]) : 3.0;
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(argv[1]))
    if (entry.is_regular_file()) files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  if (files.empty()) {
    std::fprintf(stderr, "%s: no seed files in %s\n", argv[0], argv[1]);
    return 1;
  }
  std::vector<Bytes> seeds;
  for (const auto& f : files) {
    seeds.push_back(readFile(f));
    run(seeds.back());
  }
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [&start] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  Random rng(20261123);
  long done = 0;
  for (; done < mutations && elapsed() < seconds; ++done) {
    Bytes input = seeds[rng.below(seeds.size())];
    for (std::size_t edits = 1 + rng.below(4); edits > 0; --edits) mutateOnce(input, rng);
    run(input);
  }
  std::printf("%s: %zu seed files and %ld mutations in %.1f s, no finding\n", argv[0], files.size(),
              done, elapsed());
  return 0;
}
