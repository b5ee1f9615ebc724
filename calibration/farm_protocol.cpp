// The evaluation farm's wire format; see farm_protocol.hpp.
#include "calibration/farm_protocol.hpp"

#include "calibration/farm_detail.hpp"

#include <sys/socket.h>
#include <sys/types.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <string>

namespace rsw::calibration::farm_detail {


namespace {

class ByteWriter {
 public:
  template <class T>
  void put(const T& value) {
    const auto* p = reinterpret_cast<const char*>(&value);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
  }
  void put_doubles(const Eigen::VectorXd& values) {
    const auto* p = reinterpret_cast<const char*>(values.data());
    bytes_.insert(bytes_.end(), p, p + sizeof(double) * static_cast<std::size_t>(values.size()));
  }
  void put_text(const std::string& text) { bytes_.insert(bytes_.end(), text.begin(), text.end()); }
  const std::vector<char>& bytes() const { return bytes_; }

 private:
  std::vector<char> bytes_;
};

class ByteReader {
 public:
  ByteReader(const char* data, std::size_t size) : data_(data), size_(size) {}
  template <class T>
  T get() {
    T value;
    take(&value, sizeof(T));
    return value;
  }
  Eigen::VectorXd get_doubles(std::size_t n) {
    Eigen::VectorXd values(static_cast<Eigen::Index>(n));
    take(values.data(), sizeof(double) * n);
    return values;
  }
  std::string get_text(std::size_t n) {
    std::string text(n, '\0');
    take(text.data(), n);
    return text;
  }

 private:
  void take(void* out, std::size_t n) {
    if (position_ + n > size_) throw FarmError("evaluation farm: truncated message between processes");
    std::memcpy(out, data_ + position_, n);
    position_ += n;
  }
  const char* data_;
  std::size_t size_;
  std::size_t position_ = 0;
};

}  // namespace

std::vector<char> encode_task(std::size_t index, const Eigen::VectorXd& theta) {
  ByteWriter w;
  w.put<std::uint64_t>(index);
  w.put<std::uint32_t>(static_cast<std::uint32_t>(theta.size()));
  w.put_doubles(theta);
  return w.bytes();
}

std::pair<std::size_t, Eigen::VectorXd> decode_task(const std::vector<char>& bytes) {
  ByteReader r(bytes.data(), bytes.size());
  const auto index = static_cast<std::size_t>(r.get<std::uint64_t>());
  const auto n = r.get<std::uint32_t>();
  return {index, r.get_doubles(n)};
}

std::vector<char> encode_result(const RunRecord& record) {
  ByteWriter w;
  w.put<std::uint64_t>(record.index);
  w.put<std::uint8_t>(record.ok ? 1 : 0);
  w.put<double>(record.wall_time);
  w.put<std::uint32_t>(static_cast<std::uint32_t>(record.features.size()));
  w.put<std::uint32_t>(static_cast<std::uint32_t>(record.failure_reason.size()));
  w.put<std::uint32_t>(static_cast<std::uint32_t>(record.warnings.size()));
  w.put_doubles(record.features);
  w.put_text(record.failure_reason);
  w.put_text(record.warnings);
  return w.bytes();
}

RunRecord decode_result(const char* data, std::size_t size) {
  ByteReader r(data, size);
  RunRecord record;
  record.index = static_cast<std::size_t>(r.get<std::uint64_t>());
  record.ok = r.get<std::uint8_t>() != 0;
  record.wall_time = r.get<double>();
  const auto n = r.get<std::uint32_t>();
  const auto reason_length = r.get<std::uint32_t>();
  const auto warnings_length = r.get<std::uint32_t>();
  record.features = r.get_doubles(n);
  record.failure_reason = r.get_text(reason_length);
  record.warnings = r.get_text(warnings_length);
  return record;
}


// Sends one length-prefixed frame; false if the peer is gone.
bool send_frame(int fd, const std::vector<char>& payload) {
  const auto length = static_cast<std::uint32_t>(payload.size());
  std::vector<char> frame(sizeof length);
  std::memcpy(frame.data(), &length, sizeof length);
  frame.insert(frame.end(), payload.begin(), payload.end());
  std::size_t sent = 0;
  while (sent < frame.size()) {
    const ssize_t n = ::send(fd, frame.data() + sent, frame.size() - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    sent += static_cast<std::size_t>(n);
  }
  return true;
}

// Reads exactly n bytes (blocking); false on end of file or error.
bool read_exact(int fd, char* out, std::size_t n) {
  std::size_t got = 0;
  while (got < n) {
    const ssize_t k = ::read(fd, out + got, n - got);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) return false;
    got += static_cast<std::size_t>(k);
  }
  return true;
}

std::optional<std::vector<char>> receive_frame_blocking(int fd) {
  std::uint32_t length = 0;
  if (!read_exact(fd, reinterpret_cast<char*>(&length), sizeof length)) return std::nullopt;
  std::vector<char> payload(length);
  if (!read_exact(fd, payload.data(), length)) return std::nullopt;
  return payload;
}

}  // namespace rsw::calibration::farm_detail
