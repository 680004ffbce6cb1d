#include "gpu/staging.h"

#include <algorithm>
#include <cstring>

#include "gpu/context.h"

namespace evflow::gpu {

Staging::Staging(Context& ctx) : ctx_(ctx), cb_(ctx.allocate_command_buffer()), fence_(ctx.create_fence()) {}

Staging::~Staging() {
  release_buffer();
  if (fence_) vkDestroyFence(ctx_.device(), fence_, nullptr);
  if (cb_) vkFreeCommandBuffers(ctx_.device(), ctx_.command_pool(), 1, &cb_);
}

void Staging::release_buffer() {
  VkDevice dev = ctx_.device();
  if (mapped_) vkUnmapMemory(dev, memory_);
  if (buffer_) vkDestroyBuffer(dev, buffer_, nullptr);
  if (memory_) vkFreeMemory(dev, memory_, nullptr);
  mapped_ = nullptr, buffer_ = VK_NULL_HANDLE, memory_ = VK_NULL_HANDLE, capacity_ = 0;
}

// Grows the staging buffer to hold `bytes` (a power of two from 64 KiB, at most kMaxBytes).
void Staging::reserve(uint64_t bytes) {
  bytes = std::min(bytes, kMaxBytes);
  if (bytes <= capacity_) return;
  uint64_t want = 64 << 10;
  while (want < bytes) want *= 2;
  release_buffer();
  VkDevice dev = ctx_.device();
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bci.size = want;
  bci.usage = VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  EVF_VK(vkCreateBuffer(dev, &bci, nullptr, &buffer_));
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(dev, buffer_, &req);
  const VkMemoryPropertyFlags host = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  mai.allocationSize = req.size;
  mai.memoryTypeIndex = ctx_.memory_type(req.memoryTypeBits, host, host);
  if (vkAllocateMemory(dev, &mai, nullptr, &memory_) != VK_SUCCESS) {
    memory_ = VK_NULL_HANDLE;
    release_buffer();
    throw Error("out of host-visible memory allocating a staging buffer of " + std::to_string(want) + " bytes");
  }
  EVF_VK(vkBindBufferMemory(dev, buffer_, memory_, 0));
  EVF_VK(vkMapMemory(dev, memory_, 0, VK_WHOLE_SIZE, 0, &mapped_));
  capacity_ = want;
}

void Staging::copy(VkBuffer buffer, bool to_device, void* host, uint64_t bytes, uint64_t offset) {
  std::lock_guard<std::mutex> lock(mutex_);
  reserve(bytes);
  char* h = static_cast<char*>(host);
  for (uint64_t done = 0; done < bytes;) {
    const uint64_t n = std::min(capacity_, bytes - done);
    copy_piece(buffer, to_device, h + done, n, offset + done);
    done += n;
  }
}

void Staging::copy_piece(VkBuffer buffer, bool to_device, char* host, uint64_t bytes, uint64_t offset) {
  if (to_device) std::memcpy(mapped_, host, bytes);
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  EVF_VK(vkBeginCommandBuffer(cb_, &bi));
  VkBufferCopy region{};
  region.size = bytes;
  if (to_device) {
    region.dstOffset = offset;
    vkCmdCopyBuffer(cb_, buffer_, buffer, 1, &region);
  } else {
    region.srcOffset = offset;
    vkCmdCopyBuffer(cb_, buffer, buffer_, 1, &region);
  }
  EVF_VK(vkEndCommandBuffer(cb_));
  ctx_.submit_and_wait(cb_, fence_);
  EVF_VK(vkResetCommandBuffer(cb_, 0));
  if (!to_device) std::memcpy(host, mapped_, bytes);
}

}  // namespace evflow::gpu
