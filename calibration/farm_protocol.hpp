// The evaluation farm's messages between processes (worker ↔ parent, rank ↔ rank 0):
// frames of bytes in the machine's native layout (all ranks of one study run the same
// binary on the same architecture):
//   task   = u64 index, u32 n, f64 θ[n]
//   result = u64 index, u8 ok, f64 wall_time, u32 n, u32 reason_length, f64 y[n], reason
// On a socket each frame is preceded by its u32 length. Internal to calibration/.
#pragma once

#include "calibration/farm.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <optional>
#include <utility>
#include <vector>

namespace rsw::calibration::farm_detail {

std::vector<char> encode_task(std::size_t index, const Eigen::VectorXd& theta);
std::pair<std::size_t, Eigen::VectorXd> decode_task(const std::vector<char>& bytes);
std::vector<char> encode_result(const RunRecord& record);
RunRecord decode_result(const char* data, std::size_t size);

// Sends one length-prefixed frame; false if the peer is gone.
bool send_frame(int fd, const std::vector<char>& payload);
// Reads one length-prefixed frame (blocking); nothing at end of file or on error.
std::optional<std::vector<char>> receive_frame_blocking(int fd);
// Reads exactly n bytes (blocking); false on end of file or error.
bool read_exact(int fd, char* out, std::size_t n);

}  // namespace rsw::calibration::farm_detail
