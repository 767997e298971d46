#include "fast_text.hpp"

#include <fcntl.h>
#include <fmt/compile.h>
#include <fmt/format.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstring>
#include <exception>
#include <filesystem>
#include <optional>
#include <thread>

#include "../common/memory.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/files.hpp"

namespace trueaxis::io::detail {

namespace {

// The checks every reader makes before opening `path`; returns its size when known.
std::optional<std::uintmax_t> check_readable(const std::string& path) {
  // Only regular files: a directory, a device (/dev/zero) or a pipe would either fail obscurely
  // or grow memory without limit.
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) throw Error(fmt::format("{}: no such file", path));
  if (!std::filesystem::is_regular_file(status))
    throw Error(fmt::format(
        "{}: not a regular file ({})", path,
        std::filesystem::is_directory(status) ? "a directory" : "a device, pipe or socket"));
  const auto size = std::filesystem::file_size(path, ec);
  if (!ec && size > kMaxInputBytes)
    throw Error(fmt::format(
        "{}: {:.1f} GB is more than trueaxis reads in one file ({} GB); "
        "split it",
        path, static_cast<double>(size) / 1e9, static_cast<double>(kMaxInputBytes) / 1e9));
  if (ec) return std::nullopt;
  return size;
}

std::string read_checked(const std::string& path, std::optional<std::uintmax_t> size) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) throw Error(fmt::format("{}: cannot open file for reading", path));
  std::string text;
  if (size && *size > 0) {
    // Asked for in huge pages before resize() zero-fills it: a 60 MB file is ~15 000 page faults
    // in 4 KB pages (~3 µs each on the machines we measure), ~30 in 2 MB ones.
    text.reserve(static_cast<std::size_t>(*size));
    trueaxis::detail::advise_huge_pages(text.data(), text.capacity());
    text.resize(static_cast<std::size_t>(*size));
    text.resize(std::fread(text.data(), 1, text.size(), f.get()));
  }
  char buf[1 << 16];
  std::size_t got;
  while (text.size() <= kMaxInputBytes && (got = std::fread(buf, 1, sizeof buf, f.get())) > 0)
    text.append(buf, got);
  if (std::ferror(f.get())) throw Error(fmt::format("{}: read error", path));
  if (text.size() > kMaxInputBytes)
    throw Error(fmt::format("{}: more than trueaxis reads in one file ({} GB); split it", path,
                            static_cast<double>(kMaxInputBytes) / 1e9));
  normalize_text(text);
  return text;
}

}  // namespace

std::string read_text(const std::string& path) {
  return read_checked(path, check_readable(path));
}

Text::Text(std::string text) {
  auto owned = std::make_shared<const std::string>(std::move(text));
  view_ = *owned;
  owner_ = std::move(owned);
}

Text Text::read(const std::string& path) {
  const std::optional<std::uintmax_t> size = check_readable(path);
#if defined(__linux__)
  constexpr std::uintmax_t kMapFrom = std::uintmax_t{1} << 20;
  if (size && *size >= kMapFrom) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw Error(fmt::format("{}: cannot open file for reading", path));
    const auto n = static_cast<std::size_t>(*size);
    void* m = ::mmap(nullptr, n, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
    ::close(fd);  // the mapping keeps the file
    if (m != MAP_FAILED) {
      const auto* p = static_cast<const char*>(m);
      const bool bom = n >= 3 && std::memcmp(p, "\xEF\xBB\xBF", 3) == 0;
      if (!bom && std::memchr(p, '\r', n) == nullptr) {
        Text t;
        t.owner_ = std::shared_ptr<const void>(
            m, [n](const void* q) { ::munmap(const_cast<void*>(q), n); });
        t.view_ = std::string_view(p, n);
        return t;
      }
      ::munmap(m, n);  // to be normalised: read as usual
    }
  }
#endif
  return Text(read_checked(path, size));
}

void normalize_text(std::string& text) {
  // A UTF-8 byte-order mark (spreadsheets write one) is not part of the first column's name.
  if (text.size() >= 3 && text.compare(0, 3, "\xEF\xBB\xBF") == 0) text.erase(0, 3);
  // Windows (CRLF) and old Mac (CR) line ends become LF, so that lines and columns count right.
  const std::size_t first = text.find('\r');
  if (first == std::string::npos) return;
  std::size_t out = first;
  for (std::size_t i = first; i < text.size(); ++i) {
    if (text[i] == '\r') {
      text[out++] = '\n';
      if (i + 1 < text.size() && text[i + 1] == '\n') ++i;
    } else {
      text[out++] = text[i];
    }
  }
  text.resize(out);
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string upper(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return out;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_blank(s.back())) s.remove_suffix(1);
  return s;
}

void fail_at(const std::string& path, std::size_t line, std::size_t col0, const std::string& what) {
  throw Error(fmt::format("{}:{}:{}: {}", path, line, col0 + 1, what));
}

std::string quote_cut(std::string_view s, std::size_t max) {
  const std::size_t nl = s.find('\n');
  if (nl != std::string_view::npos) s = s.substr(0, nl);
  if (s.size() <= max) return std::string(s);
  return std::string(s.substr(0, max)) + "...";
}

int workers_for(std::size_t n) {
  constexpr std::size_t kMinPerWorker = 1 << 16;
  // Asked once: glibc answers hardware_concurrency() by reading /sys on every call, which made a
  // loop of small evaluations (a parametric correction per gauge block) spend its time in open().
  static const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  const std::size_t by_size = std::max<std::size_t>(1, n / kMinPerWorker);
  return static_cast<int>(std::min<std::size_t>({hw, by_size, 8}));
}

void parallel_ranges(std::size_t n, int workers,
                     const std::function<void(int, std::size_t, std::size_t)>& fn) {
  workers = std::max(1, workers);
  std::vector<std::exception_ptr> errors(static_cast<std::size_t>(workers));
  auto run = [&](int t) {
    const std::size_t b = n * static_cast<std::size_t>(t) / static_cast<std::size_t>(workers);
    const std::size_t e = n * static_cast<std::size_t>(t + 1) / static_cast<std::size_t>(workers);
    try {
      fn(t, b, e);
    } catch (...) {
      errors[static_cast<std::size_t>(t)] = std::current_exception();
    }
  };
  std::vector<std::thread> threads;
  threads.reserve(static_cast<std::size_t>(workers - 1));
  for (int t = 0; t + 1 < workers; ++t) threads.emplace_back(run, t);
  run(workers - 1);
  for (auto& th : threads) th.join();
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
}

char* write_number(char* p, double v) {
  return fmt::format_to(p, FMT_COMPILE("{}"), v);
}

namespace {
int flush_only(std::FILE* f) {
  return std::fflush(f);
}
}  // namespace

OutFile::OutFile(const std::string& path)
    : path_(path == "-" ? "standard output" : path), f_(nullptr, &std::fclose) {
  if (path == "-") {
    f_ = std::unique_ptr<std::FILE, int (*)(std::FILE*)>(stdout, &flush_only);
    return;
  }
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path p(path);
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
  if (!fs::is_directory(dir, ec))
    throw Error(
        fmt::format("{}: the directory '{}' does not exist (create it first)", path, dir.string()));
  if (fs::is_directory(p, ec)) throw Error(fmt::format("{}: is a directory", path));
  const auto st = fs::status(p, ec);
  if (!ec && fs::exists(st) && !fs::is_regular_file(st)) {
    f_.reset(std::fopen(path.c_str(), "wb"));  // a device or pipe: write to it directly
  } else {
    static std::atomic<unsigned> counter{0};
    target_ = path;
    partial_ = fmt::format("{}.partial-{}-{}", path, static_cast<long>(getpid()), counter++);
    f_.reset(std::fopen(partial_.c_str(), "wb"));
  }
  if (!f_) throw Error(fmt::format("{}: cannot open file for writing", path));
}

void OutFile::write(std::string_view s) {
  if (!f_) throw Error(fmt::format("{}: file already closed", path_));
  if (!s.empty() && std::fwrite(s.data(), 1, s.size(), f_.get()) != s.size())
    throw Error(fmt::format("{}: write error", path_));
}

namespace {
// Sizes a piece for `chars` characters. New memory is asked for in huge pages before resize()
// zero-fills it (a fresh piece of a 10⁶-number array is ~6 MB).
void size_piece(std::string& s, std::size_t chars) {
  if (s.capacity() < chars) {
    s.clear();
    s.reserve(chars);
    trueaxis::detail::advise_huge_pages(s.data(), s.capacity());
  }
  s.resize(chars);
}
}  // namespace

void format_numbers(const double* v, std::size_t n, double scale, char sep,
                    std::vector<std::string>& pieces) {
  constexpr std::size_t kMaxChars = 26;  // 24 for a double, one separator, one spare
  const int w = workers_for(n);
  pieces.resize(static_cast<std::size_t>(w));
  parallel_ranges(n, w, [&](int t, std::size_t b, std::size_t e) {
    std::string& s = pieces[static_cast<std::size_t>(t)];
    size_piece(s, (e - b) * kMaxChars);
    char* p = s.data();
    for (std::size_t i = b; i < e; ++i) {
      if (i) *p++ = sep;
      p = write_number(p, v[i] * scale);
    }
    s.resize(static_cast<std::size_t>(p - s.data()));
  });
}

void format_rows(const std::vector<const double*>& columns, std::size_t n,
                 std::vector<std::string>& pieces) {
  const std::size_t per_row = columns.size() * 26 + 1;
  const int w = workers_for(n * columns.size());
  pieces.resize(static_cast<std::size_t>(w));
  parallel_ranges(n, w, [&](int t, std::size_t b, std::size_t e) {
    std::string& s = pieces[static_cast<std::size_t>(t)];
    size_piece(s, (e - b) * per_row);
    char* p = s.data();
    for (std::size_t i = b; i < e; ++i) {
      for (std::size_t c = 0; c < columns.size(); ++c) {
        if (c) *p++ = ',';
        const double v = columns[c][i];
        if (v == v) p = write_number(p, v);  // NaN: empty field
      }
      *p++ = '\n';
    }
    s.resize(static_cast<std::size_t>(p - s.data()));
  });
}

void OutFile::numbers(const double* v, std::size_t n, double scale, char sep) {
  format_numbers(v, n, scale, sep, pieces_);
  write(pieces_);
}

void OutFile::write(const std::vector<std::string>& pieces) {
  for (const auto& s : pieces) write(s);
}

void OutFile::close() {
  if (!f_) return;
  const bool ok = std::fflush(f_.get()) == 0 && !std::ferror(f_.get());
  auto* deleter = f_.get_deleter();
  const bool closed = deleter(f_.release()) == 0;
  if (!ok || !closed) {
    if (!partial_.empty()) std::remove(partial_.c_str());
    partial_.clear();
    throw Error(fmt::format("{}: write error (disk full?); nothing was written", path_));
  }
  if (!partial_.empty()) {
    std::error_code ec;
    std::filesystem::rename(partial_, target_, ec);
    if (ec) {
      std::remove(partial_.c_str());
      partial_.clear();
      throw Error(fmt::format("{}: cannot put the file in place: {}", path_, ec.message()));
    }
    partial_.clear();
  }
}

OutFile::~OutFile() {
  if (f_ && !partial_.empty()) {  // never closed: an exception on the way; keep the old file
    auto* deleter = f_.get_deleter();
    deleter(f_.release());
    std::remove(partial_.c_str());
    return;
  }
  try {
    close();
  } catch (...) {
  }
}

}  // namespace trueaxis::io::detail

namespace trueaxis::io {

void write_text(const std::string& path, std::string_view text) {
  detail::OutFile f(path);
  f.write(text);
  f.close();
}

}  // namespace trueaxis::io
