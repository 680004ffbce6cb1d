// Staging: the host-visible buffer, command buffer and fence through which a device without
// host-visible device memory (a discrete GPU) uploads to and downloads from its buffers. One per
// context, made on first use and kept: a copy then costs one submit and one wait, not the
// allocation, mapping and freeing of a buffer and a command buffer each time. Copies larger than
// the staging buffer's cap go through it in pieces.
#pragma once
#include <vulkan/vulkan.h>

#include <cstdint>
#include <mutex>

namespace evflow::gpu {

class Context;

class Staging {
 public:
  static constexpr uint64_t kMaxBytes = 64ull << 20;  // the staging buffer grows up to this

  explicit Staging(Context& ctx);
  ~Staging();
  Staging(const Staging&) = delete;
  Staging& operator=(const Staging&) = delete;

  // Copies `bytes` between host memory and `buffer` at `offset`, and waits for the copy.
  void copy(VkBuffer buffer, bool to_device, void* host, uint64_t bytes, uint64_t offset);

  uint64_t capacity() const { return capacity_; }

 private:
  void reserve(uint64_t bytes);
  void release_buffer();
  void copy_piece(VkBuffer buffer, bool to_device, char* host, uint64_t bytes, uint64_t offset);
  Context& ctx_;
  std::mutex mutex_;
  VkBuffer buffer_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  void* mapped_ = nullptr;
  uint64_t capacity_ = 0;
  VkCommandBuffer cb_ = VK_NULL_HANDLE;
  VkFence fence_ = VK_NULL_HANDLE;
};

}  // namespace evflow::gpu
