#include "output.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iomanip>
#include <random>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "output_internal.hpp"

namespace liedyn {
namespace internal {

std::string error_text(int error) { return std::strerror(error); }

namespace {

// Six characters from 62 (35 bits), as mkstemp; with O_EXCL a clash is only a retry.
std::string random_suffix() {
  static thread_local std::mt19937_64 generator{std::random_device{}()};
  static constexpr char kAlphabet[] =
      "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789";
  std::string s(6, 'x');
  for (char& c : s) c = kAlphabet[generator() % (sizeof kAlphabet - 1)];
  return s;
}

template <class Create>
int create_unique(const std::string& prefix, const std::string& where, std::string& name,
                  Create create) {
  for (int attempt = 0; attempt < 100; ++attempt) {
    name = prefix + random_suffix();
    const int fd = create(name);
    if (fd >= 0) return fd;
    if (errno != EEXIST) {
      throw std::runtime_error(where + ": cannot create a temporary file: " + error_text(errno));
    }
  }
  throw std::runtime_error(where + ": cannot create a temporary file: 100 names taken");
}

// The removal list read by the signal handler: fixed storage and atomics only, since a
// handler may not allocate or take locks.
struct RemovalSlot {
  std::atomic<int> state{0};  // 0 free, 1 being filled, 2 registered
  int dirfd = -1;
  bool is_folder = false;
  char name[256] = {};
};
std::array<RemovalSlot, 256> removal_slots;

extern "C" void remove_outputs_and_exit(int signal) {
  for (const bool folders : {false, true}) {
    for (RemovalSlot& slot : removal_slots) {
      if (slot.state.load() == 2 && slot.is_folder == folders) {
        ::unlinkat(slot.dirfd, slot.name, folders ? AT_REMOVEDIR : 0);
      }
    }
  }
  ::_exit(128 + signal);
}

constexpr int kTerminatingSignals[] = {SIGINT, SIGTERM, SIGHUP};

}  // namespace

int create_unique_file(int dirfd, const std::string& prefix, const std::string& where,
                       std::string& name) {
  return create_unique(prefix, where, name, [dirfd](const std::string& n) {
    return ::openat(dirfd, n.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
  });
}

int create_unique_folder(int dirfd, const std::string& prefix, const std::string& where,
                         std::string& name) {
  return create_unique(prefix, where, name, [dirfd](const std::string& n) {
    if (::mkdirat(dirfd, n.c_str(), 0700) != 0) return -1;
    const int fd = ::openat(dirfd, n.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
    if (fd < 0) {
      const int error = errno;
      ::unlinkat(dirfd, n.c_str(), AT_REMOVEDIR);
      errno = error == EEXIST ? EIO : error;  // not a name clash: do not retry
    }
    return fd;
  });
}

int register_removal(int dirfd, const std::string& name, bool is_folder) {
  if (name.size() >= sizeof(RemovalSlot::name)) {
    throw std::logic_error("register_removal: name too long: " + name);
  }
  for (std::size_t i = 0; i < removal_slots.size(); ++i) {
    RemovalSlot& slot = removal_slots[i];
    int expected = 0;
    if (!slot.state.compare_exchange_strong(expected, 1)) continue;
    slot.dirfd = dirfd;
    slot.is_folder = is_folder;
    std::memcpy(slot.name, name.c_str(), name.size() + 1);
    slot.state.store(2);
    return static_cast<int>(i);
  }
  throw std::logic_error("register_removal: more than 256 output files open at once");
}

void release_removal(int slot) {
  if (slot >= 0) removal_slots[static_cast<std::size_t>(slot)].state.store(0);
}

static_assert(sizeof(sigset_t) <= sizeof(unsigned long long[16]));

SignalBlock::SignalBlock() {
  sigset_t block;
  sigemptyset(&block);
  for (const int s : kTerminatingSignals) sigaddset(&block, s);
  ::pthread_sigmask(SIG_BLOCK, &block, reinterpret_cast<sigset_t*>(saved_));
}

SignalBlock::~SignalBlock() {
  ::pthread_sigmask(SIG_SETMASK, reinterpret_cast<const sigset_t*>(saved_), nullptr);
}

}  // namespace internal

void install_output_signal_handlers() {
  struct sigaction action {};
  action.sa_handler = internal::remove_outputs_and_exit;
  sigemptyset(&action.sa_mask);
  for (const int s : internal::kTerminatingSignals) sigaddset(&action.sa_mask, s);
  for (const int s : internal::kTerminatingSignals) ::sigaction(s, &action, nullptr);
  ::signal(SIGXFSZ, SIG_IGN);
}

// ---------------------------------------------------------------------------------------------

class FileStream::Buffer : public std::streambuf {
 public:
  explicit Buffer(int fd) : fd_(fd), data_(1 << 16) { setp(data_.data(), data_.data() + data_.size()); }
  ~Buffer() override {
    if (fd_ >= 0) ::close(fd_);
  }

  // Writes out the buffer, then fsyncs and closes; the first error, or 0.
  int finish() {
    drain();
    if (error_ == 0 && ::fsync(fd_) != 0 && errno != EINVAL) error_ = errno;
    if (::close(fd_) != 0 && error_ == 0) error_ = errno;
    fd_ = -1;
    return error_;
  }

 protected:
  int_type overflow(int_type ch) override {
    if (!drain()) return traits_type::eof();
    if (!traits_type::eq_int_type(ch, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(ch);
      pbump(1);
    }
    return traits_type::not_eof(ch);
  }
  int sync() override { return drain() ? 0 : -1; }

 private:
  bool drain() {
    const char* p = pbase();
    while (error_ == 0 && p < pptr()) {
      const ssize_t n = ::write(fd_, p, static_cast<std::size_t>(pptr() - p));
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) error_ = errno;
      else p += n;
    }
    setp(data_.data(), data_.data() + data_.size());
    return error_ == 0;
  }

  int fd_;
  int error_ = 0;
  std::vector<char> data_;
};

FileStream::FileStream(int fd) : buffer_(std::make_unique<Buffer>(fd)), stream_(buffer_.get()) {
  stream_.precision(17);
}

FileStream::~FileStream() = default;

std::ostream& FileStream::stream() { return stream_; }

void FileStream::finish(const std::string& what) {
  stream_.flush();
  const int error = buffer_->finish();
  if (error != 0) throw std::runtime_error(what + ": write failed: " + internal::error_text(error));
}

// ---------------------------------------------------------------------------------------------

namespace {

// The folder of `target`, opened (errors name the target).
int open_folder(const std::filesystem::path& target) {
  const std::filesystem::path folder = target.parent_path().empty() ? "." : target.parent_path();
  const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) {
    throw std::runtime_error(target.string() + ": cannot open its folder: " +
                             internal::error_text(errno));
  }
  return fd;
}

}  // namespace

AtomicFile::AtomicFile(std::filesystem::path target) : target_(std::move(target)) {
  const int dirfd = open_folder(target_);
  std::string prefix = ".";  // appended, not "." + …: GCC 12 warns falsely (-Wrestrict) there
  prefix += target_.filename().string();
  prefix += ".liedyn-";
  std::string name;
  int fd = -1;
  try {
    fd = internal::create_unique_file(dirfd, prefix, target_.string(), name);
  } catch (...) {
    ::close(dirfd);
    throw;
  }
  dirfd_ = dirfd;
  temporary_ = name;
  cleanup_slot_ = internal::register_removal(dirfd_, name, false);
  file_ = std::make_unique<FileStream>(fd);
}

AtomicFile::~AtomicFile() {
  if (!committed_) {
    file_.reset();
    ::unlinkat(dirfd_, temporary_.c_str(), 0);
    internal::release_removal(cleanup_slot_);
  }
  ::close(dirfd_);
}

void AtomicFile::commit() {
  file_->finish(target_.string());
  const internal::SignalBlock hold;
  if (::renameat(dirfd_, temporary_.c_str(), dirfd_, target_.filename().c_str()) != 0) {
    throw std::runtime_error(target_.string() + ": cannot rename into place: " +
                             internal::error_text(errno));
  }
  committed_ = true;
  internal::release_removal(cleanup_slot_);
}

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string out = "\"";
  for (const char ch : text) out += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return out + "\"";
}

std::string format_number(double value, int digits) {
  if (std::isnan(value)) return "nan";
  std::ostringstream os;
  os << std::setprecision(digits) << value;
  return os.str();
}

std::string json_quoted(const std::string& text) {
  std::string out = "\"";
  for (const char ch : text) {
    if (ch == '"' || ch == '\\') {
      out += '\\';
      out += ch;
    } else if (static_cast<unsigned char>(ch) < 0x20) {
      char code[8];
      std::snprintf(code, sizeof code, "\\u%04x", static_cast<unsigned>(ch));
      out += code;
    } else {
      out += ch;
    }
  }
  return out + "\"";
}

}  // namespace liedyn
