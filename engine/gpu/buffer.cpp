#include "gpu/buffer.h"

#include "gpu/staging.h"

#include <cstring>
#include <utility>

namespace evflow::gpu {

Buffer::Buffer(Context& ctx, uint64_t bytes, std::string name) : ctx_(&ctx), name_(std::move(name)) { allocate(bytes); }

Buffer::~Buffer() { release(); }

Buffer::Buffer(Buffer&& o) noexcept { *this = std::move(o); }

Buffer& Buffer::operator=(Buffer&& o) noexcept {
  if (this != &o) {
    release();
    ctx_ = o.ctx_;
    name_ = std::move(o.name_);
    size_ = o.size_;
    allocated_ = std::exchange(o.allocated_, 0);
    serial_ = std::exchange(o.serial_, 0);
    buffer_ = std::exchange(o.buffer_, VK_NULL_HANDLE);
    memory_ = std::exchange(o.memory_, VK_NULL_HANDLE);
    mapped_ = std::exchange(o.mapped_, nullptr);
    o.size_ = 0;
  }
  return *this;
}

void Buffer::release() {
  if (!ctx_) return;
  if (buffer_) vkDestroyBuffer(ctx_->device(), buffer_, nullptr);
  if (memory_) vkFreeMemory(ctx_->device(), memory_, nullptr);
  if (allocated_) ctx_->count_allocation(-int64_t(allocated_));
  if (serial_) ctx_->release_allocation(serial_);
  serial_ = 0;
  allocated_ = 0;
  buffer_ = VK_NULL_HANDLE;
  memory_ = VK_NULL_HANDLE;
  mapped_ = nullptr;
  size_ = 0;
}

void Buffer::allocate(uint64_t bytes) {
  bytes = std::max<uint64_t>(16, (bytes + 15) & ~uint64_t(15));
  if (bytes > ctx_->caps().max_allocation_size)
    throw Error("buffer '" + name_ + "' needs " + std::to_string(bytes) +
                " bytes, above this device's largest allocation (" + std::to_string(ctx_->caps().max_allocation_size) +
                " bytes)");
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bci.size = bytes;
  bci.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT |
              VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  bci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  EVF_VK(vkCreateBuffer(ctx_->device(), &bci, nullptr, &buffer_));
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(ctx_->device(), buffer_, &req);
  VkMemoryPropertyFlags required = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
  VkMemoryPropertyFlags preferred = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
  if (ctx_->caps().unified_memory) {
    required = preferred = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    preferred |= VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
  }
  VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  mai.allocationSize = req.size;
  mai.memoryTypeIndex = ctx_->memory_type(req.memoryTypeBits, required, preferred);
  VkResult r = vkAllocateMemory(ctx_->device(), &mai, nullptr, &memory_);
  if (r != VK_SUCCESS)
    throw Error("out of device memory allocating buffer '" + name_ + "' of " + std::to_string(bytes) + " bytes");
  allocated_ = req.size;
  ctx_->count_allocation(int64_t(allocated_));
  EVF_VK(vkBindBufferMemory(ctx_->device(), buffer_, memory_, 0));
  serial_ = ctx_->register_allocation();
  size_ = bytes;
  if (ctx_->caps().unified_memory) EVF_VK(vkMapMemory(ctx_->device(), memory_, 0, VK_WHOLE_SIZE, 0, &mapped_));
  if (ctx_->options().poison) {
    if (mapped_) {
      std::memset(mapped_, 0xFF, size_);
    } else {
      std::vector<uint8_t> p(size_, 0xFF);
      staged_copy(true, p.data(), size_, 0);
    }
  }
}

void Buffer::ensure(uint64_t bytes) {
  if (bytes <= size_) return;
  uint64_t want = bytes + bytes / 4;
  release();
  allocate(want);
}

void Buffer::upload(const void* data, uint64_t bytes, uint64_t offset) {
  if (offset + bytes > size_)
    throw Error("upload of " + std::to_string(bytes) + " bytes at " + std::to_string(offset) + " overflows buffer '" +
                name_ + "'");
  ctx_->count_transfer();
  if (mapped_)
    std::memcpy(static_cast<char*>(mapped_) + offset, data, bytes);
  else
    staged_copy(true, const_cast<void*>(data), bytes, offset);
}

void Buffer::download(void* data, uint64_t bytes, uint64_t offset) const {
  if (offset + bytes > size_)
    throw Error("download of " + std::to_string(bytes) + " bytes at " + std::to_string(offset) + " overflows buffer '" +
                name_ + "'");
  ctx_->count_transfer();
  if (mapped_)
    std::memcpy(data, static_cast<const char*>(mapped_) + offset, bytes);
  else
    staged_copy(false, data, bytes, offset);
}

// For devices whose device-local memory is not host-visible: through the context's staging
// buffer, one submit and one wait per copy.
void Buffer::staged_copy(bool to_device, void* host, uint64_t bytes, uint64_t offset) const {
  ctx_->staging().copy(buffer_, to_device, host, bytes, offset);
}

}  // namespace evflow::gpu
