// A storage buffer with its own memory. Fresh buffers are poisoned (all bits set, which reads
// as NaN in float and 0xFFFFFFFF in uint) when the context asks for it, so that code that relies
// on zeroed memory fails in tests.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "gpu/context.h"

namespace evflow::gpu {

class Buffer {
 public:
  Buffer() = default;
  Buffer(Context& ctx, uint64_t bytes, std::string name);
  ~Buffer();
  Buffer(Buffer&& o) noexcept;
  Buffer& operator=(Buffer&& o) noexcept;
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;

  bool valid() const { return buffer_ != VK_NULL_HANDLE; }
  // The size in bytes: what was asked for, rounded up to a whole number of 16 bytes (so a kernel
  // may read a buffer's last, partly used vec4 as one RGBA32F texel).
  uint64_t size() const { return size_; }
  VkBuffer handle() const { return buffer_; }
  const std::string& name() const { return name_; }
  Context& context() const { return *ctx_; }
  uint64_t serial() const { return serial_; }  // of the current allocation (Context::register_allocation)

  // Grows (reallocates, contents lost) when smaller than `bytes`; keeps 25% headroom.
  void ensure(uint64_t bytes);

  void upload(const void* data, uint64_t bytes, uint64_t offset = 0);
  void download(void* data, uint64_t bytes, uint64_t offset = 0) const;

  template <class T>
  void write(const std::vector<T>& v, uint64_t offset = 0) {
    if (!v.empty()) upload(v.data(), v.size() * sizeof(T), offset);
  }
  template <class T>
  std::vector<T> read(size_t count, uint64_t offset = 0) const {
    std::vector<T> v(count);
    if (count) download(v.data(), count * sizeof(T), offset);
    return v;
  }
  template <class T>
  T read_one(size_t index) const {
    T v;
    download(&v, sizeof(T), index * sizeof(T));
    return v;
  }

 private:
  void allocate(uint64_t bytes);
  void release();
  void staged_copy(bool to_device, void* host, uint64_t bytes, uint64_t offset) const;
  Context* ctx_ = nullptr;
  std::string name_;
  uint64_t size_ = 0;
  uint64_t allocated_ = 0;  // the memory behind it (counted in Context::device_bytes)
  uint64_t serial_ = 0;     // Context::register_allocation's, 0 when unallocated
  VkBuffer buffer_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  void* mapped_ = nullptr;
};

// A view of part of a buffer, as bound to one descriptor.
struct BufferRef {
  const Buffer* buffer = nullptr;
  uint64_t offset = 0;
  uint64_t range = 0;                         // 0 = to the end
  BufferRef(const Buffer& b) : buffer(&b) {}  // NOLINT(google-explicit-constructor)
  BufferRef(const Buffer& b, uint64_t off, uint64_t r) : buffer(&b), offset(off), range(r) {}
};

}  // namespace evflow::gpu
