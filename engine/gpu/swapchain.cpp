#include "gpu/swapchain.h"

#include <algorithm>

namespace evflow::gpu {

const char* present_mode_name(VkPresentModeKHR m) {
  switch (m) {
    case VK_PRESENT_MODE_IMMEDIATE_KHR:
      return "immediate";
    case VK_PRESENT_MODE_MAILBOX_KHR:
      return "mailbox";
    case VK_PRESENT_MODE_FIFO_KHR:
      return "fifo";
    case VK_PRESENT_MODE_FIFO_RELAXED_KHR:
      return "fifo-relaxed";
    default:
      return "other";
  }
}

static const char* format_name(VkFormat f) {
  switch (f) {
    case VK_FORMAT_B8G8R8A8_UNORM:
      return "B8G8R8A8_UNORM";
    case VK_FORMAT_B8G8R8A8_SRGB:
      return "B8G8R8A8_SRGB";
    case VK_FORMAT_R8G8B8A8_UNORM:
      return "R8G8B8A8_UNORM";
    case VK_FORMAT_R8G8B8A8_SRGB:
      return "R8G8B8A8_SRGB";
    default:
      return "?";
  }
}

SwapchainSupport Swapchain::query(const Context& ctx, VkSurfaceKHR surface) {
  SwapchainSupport s;
  VkPhysicalDevice pd = ctx.physical();
  EVF_VK(vkGetPhysicalDeviceSurfaceCapabilitiesKHR(pd, surface, &s.caps));
  uint32_t n = 0;
  EVF_VK(vkGetPhysicalDeviceSurfaceFormatsKHR(pd, surface, &n, nullptr));
  s.formats.resize(n);
  EVF_VK(vkGetPhysicalDeviceSurfaceFormatsKHR(pd, surface, &n, s.formats.data()));
  s.formats.resize(n);
  n = 0;
  EVF_VK(vkGetPhysicalDeviceSurfacePresentModesKHR(pd, surface, &n, nullptr));
  s.present_modes.resize(n);
  EVF_VK(vkGetPhysicalDeviceSurfacePresentModesKHR(pd, surface, &n, s.present_modes.data()));
  s.present_modes.resize(n);
  return s;
}

Swapchain::Swapchain(Context& ctx, VkSurfaceKHR surface, uint32_t width, uint32_t height, bool vsync)
    : ctx_(ctx), surface_(surface), vsync_(vsync) {
  try {
    ctx_.require_present(surface_);
    VkSemaphoreCreateInfo sci{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    EVF_VK(vkCreateSemaphore(ctx_.device(), &sci, nullptr, &acquired_));
    VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    EVF_VK(vkCreateFence(ctx_.device(), &fci, nullptr, &fence_));
    VkCommandBufferAllocateInfo cai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    cai.commandPool = ctx_.command_pool();
    cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    cai.commandBufferCount = 1;
    EVF_VK(vkAllocateCommandBuffers(ctx_.device(), &cai, &cb_));
    build(width, height);
  } catch (...) {
    cleanup();
    throw;
  }
}

Swapchain::~Swapchain() { cleanup(); }

void Swapchain::cleanup() {
  VkDevice d = ctx_.device();
  if (d) vkDeviceWaitIdle(d);
  destroy_swapchain(swapchain_);
  swapchain_ = VK_NULL_HANDLE;
  if (cb_) vkFreeCommandBuffers(d, ctx_.command_pool(), 1, &cb_);
  cb_ = VK_NULL_HANDLE;
  if (fence_) vkDestroyFence(d, fence_, nullptr);
  fence_ = VK_NULL_HANDLE;
  if (acquired_) vkDestroySemaphore(d, acquired_, nullptr);
  acquired_ = VK_NULL_HANDLE;
  if (render_pass_) vkDestroyRenderPass(d, render_pass_, nullptr);
  render_pass_ = VK_NULL_HANDLE;
  if (surface_) vkDestroySurfaceKHR(ctx_.instance(), surface_, nullptr);
  surface_ = VK_NULL_HANDLE;
}

void Swapchain::destroy_swapchain(VkSwapchainKHR sc) {
  VkDevice d = ctx_.device();
  for (VkSemaphore s : render_done_) vkDestroySemaphore(d, s, nullptr);
  render_done_.clear();
  for (VkFramebuffer f : framebuffers_) vkDestroyFramebuffer(d, f, nullptr);
  framebuffers_.clear();
  for (VkImageView v : views_) vkDestroyImageView(d, v, nullptr);
  views_.clear();
  images_.clear();
  if (sc) vkDestroySwapchainKHR(d, sc, nullptr);
}

void Swapchain::recreate(uint32_t width, uint32_t height) {
  vkDeviceWaitIdle(ctx_.device());
  build(width, height);
}

void Swapchain::build(uint32_t width, uint32_t height) {
  VkDevice d = ctx_.device();
  SwapchainSupport s = query(ctx_, surface_);
  if (!(s.caps.supportedUsageFlags & VK_IMAGE_USAGE_TRANSFER_DST_BIT))
    throw Error(ctx_.caps().name + ": swapchain images of this surface cannot be transfer destinations");
  // Extent: the surface's when it fixes one, else the window's clamped to the limits.
  VkExtent2D ext = s.caps.currentExtent;
  if (ext.width == 0xFFFFFFFFu) {
    ext.width = std::clamp(width, s.caps.minImageExtent.width, s.caps.maxImageExtent.width);
    ext.height = std::clamp(height, s.caps.minImageExtent.height, s.caps.maxImageExtent.height);
  }
  if (ext.width == 0 || ext.height == 0 || width == 0 || height == 0) {  // minimised: keep nothing
    destroy_swapchain(swapchain_);
    swapchain_ = VK_NULL_HANDLE;
    extent_ = {0, 0};
    return;
  }
  // Format: 8-bit RGBA/BGRA (UNORM preferred; the pack kernel writes sRGB-encoded bytes and a
  // copy does not convert, so the _SRGB variants show the same thing).
  const VkFormat wanted[] = {VK_FORMAT_B8G8R8A8_UNORM, VK_FORMAT_R8G8B8A8_UNORM, VK_FORMAT_B8G8R8A8_SRGB,
                             VK_FORMAT_R8G8B8A8_SRGB};
  bool found = false;
  for (VkFormat f : wanted) {
    for (const auto& sf : s.formats)
      if (sf.format == f && sf.colorSpace == VK_COLOR_SPACE_SRGB_NONLINEAR_KHR) {
        format_ = sf;
        found = true;
        break;
      }
    if (found) break;
  }
  if (!found) throw Error(ctx_.caps().name + ": the surface offers no 8-bit RGBA/BGRA sRGB-nonlinear format");
  if (render_pass_ && format_.format != rp_format_)
    throw Error("Swapchain: the surface's format changed on a rebuild (" + std::string(format_name(format_.format)) +
                ", was " + format_name(rp_format_) + ")");
  bgr_ = format_.format == VK_FORMAT_B8G8R8A8_UNORM || format_.format == VK_FORMAT_B8G8R8A8_SRGB;
  auto has_mode = [&](VkPresentModeKHR m) {
    return std::find(s.present_modes.begin(), s.present_modes.end(), m) != s.present_modes.end();
  };
  mode_ = VK_PRESENT_MODE_FIFO_KHR;  // always supported
  if (!vsync_) {
    if (has_mode(VK_PRESENT_MODE_MAILBOX_KHR))
      mode_ = VK_PRESENT_MODE_MAILBOX_KHR;
    else if (has_mode(VK_PRESENT_MODE_IMMEDIATE_KHR))
      mode_ = VK_PRESENT_MODE_IMMEDIATE_KHR;
  }
  uint32_t count = s.caps.minImageCount + 1;
  if (s.caps.maxImageCount) count = std::min(count, s.caps.maxImageCount);
  VkCompositeAlphaFlagBitsKHR alpha = VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR;
  if (!(s.caps.supportedCompositeAlpha & alpha)) {
    for (VkCompositeAlphaFlagBitsKHR a : {VK_COMPOSITE_ALPHA_INHERIT_BIT_KHR, VK_COMPOSITE_ALPHA_PRE_MULTIPLIED_BIT_KHR,
                                          VK_COMPOSITE_ALPHA_POST_MULTIPLIED_BIT_KHR})
      if (s.caps.supportedCompositeAlpha & a) {
        alpha = a;
        break;
      }
  }
  VkSwapchainCreateInfoKHR ci{VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR};
  ci.surface = surface_;
  ci.minImageCount = count;
  ci.imageFormat = format_.format;
  ci.imageColorSpace = format_.colorSpace;
  ci.imageExtent = ext;
  ci.imageArrayLayers = 1;
  // Colour attachment: drawing over the copied frame; transfer source: reading it back.
  const VkImageUsageFlags extra = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  can_draw_over_ = (s.caps.supportedUsageFlags & extra) == extra;
  ci.imageUsage = VK_IMAGE_USAGE_TRANSFER_DST_BIT | (can_draw_over_ ? extra : 0);
  ci.imageSharingMode = VK_SHARING_MODE_EXCLUSIVE;
  ci.preTransform = (s.caps.supportedTransforms & VK_SURFACE_TRANSFORM_IDENTITY_BIT_KHR)
                        ? VK_SURFACE_TRANSFORM_IDENTITY_BIT_KHR
                        : s.caps.currentTransform;
  ci.compositeAlpha = alpha;
  ci.presentMode = mode_;
  ci.clipped = VK_TRUE;
  ci.oldSwapchain = swapchain_;
  VkSwapchainKHR fresh = VK_NULL_HANDLE;
  EVF_VK(vkCreateSwapchainKHR(d, &ci, nullptr, &fresh));
  destroy_swapchain(swapchain_);
  swapchain_ = fresh;
  extent_ = ext;
  uint32_t n = 0;
  EVF_VK(vkGetSwapchainImagesKHR(d, swapchain_, &n, nullptr));
  images_.resize(n);
  EVF_VK(vkGetSwapchainImagesKHR(d, swapchain_, &n, images_.data()));
  images_.resize(n);
  render_done_.assign(n, VK_NULL_HANDLE);
  VkSemaphoreCreateInfo sci{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
  for (auto& sem : render_done_) EVF_VK(vkCreateSemaphore(d, &sci, nullptr, &sem));
  min_images_ = std::max(2u, s.caps.minImageCount);
  if (can_draw_over_) make_framebuffers();
  needs_recreate_ = false;
}

void Swapchain::make_render_pass() {
  VkAttachmentDescription a{};
  a.format = format_.format;
  a.samples = VK_SAMPLE_COUNT_1_BIT;
  a.loadOp = VK_ATTACHMENT_LOAD_OP_LOAD;  // the copied frame stays; the UI draws over it
  a.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  a.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
  a.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
  a.initialLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  a.finalLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  VkAttachmentReference ref{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
  VkSubpassDescription sub{};
  sub.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
  sub.colorAttachmentCount = 1;
  sub.pColorAttachments = &ref;
  // The barriers around the pass (present()) order it with the copy before and the readback or
  // presentation after; these dependencies state the same for the pass itself.
  VkSubpassDependency deps[2]{};
  deps[0].srcSubpass = VK_SUBPASS_EXTERNAL;
  deps[0].dstSubpass = 0;
  deps[0].srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  deps[0].dstStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  deps[0].srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  deps[0].dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  deps[1].srcSubpass = 0;
  deps[1].dstSubpass = VK_SUBPASS_EXTERNAL;
  deps[1].srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  deps[1].dstStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  deps[1].srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  deps[1].dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  VkRenderPassCreateInfo ci{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
  ci.attachmentCount = 1;
  ci.pAttachments = &a;
  ci.subpassCount = 1;
  ci.pSubpasses = &sub;
  ci.dependencyCount = 2;
  ci.pDependencies = deps;
  EVF_VK(vkCreateRenderPass(ctx_.device(), &ci, nullptr, &render_pass_));
  rp_format_ = format_.format;
}

void Swapchain::make_framebuffers() {
  VkDevice d = ctx_.device();
  if (!render_pass_) make_render_pass();
  views_.assign(images_.size(), VK_NULL_HANDLE);
  framebuffers_.assign(images_.size(), VK_NULL_HANDLE);
  for (size_t i = 0; i < images_.size(); ++i) {
    VkImageViewCreateInfo vi{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vi.image = images_[i];
    vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
    vi.format = format_.format;
    vi.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    EVF_VK(vkCreateImageView(d, &vi, nullptr, &views_[i]));
    VkFramebufferCreateInfo fi{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    fi.renderPass = render_pass_;
    fi.attachmentCount = 1;
    fi.pAttachments = &views_[i];
    fi.width = extent_.width;
    fi.height = extent_.height;
    fi.layers = 1;
    EVF_VK(vkCreateFramebuffer(d, &fi, nullptr, &framebuffers_[i]));
  }
}

bool Swapchain::present(const Buffer& rgba8, const DrawOver& draw_over, Buffer* readback) {
  if (!swapchain_) return false;
  const uint64_t bytes = uint64_t(extent_.width) * extent_.height * 4;
  auto check_size = [&](const Buffer& b) {
    if (b.size() < bytes)
      throw Error("Swapchain::present: buffer '" + b.name() + "' holds " + std::to_string(b.size()) + " bytes, the " +
                  std::to_string(extent_.width) + "x" + std::to_string(extent_.height) + " image needs " +
                  std::to_string(bytes));
  };
  check_size(rgba8);
  if (readback) check_size(*readback);
  if ((draw_over || readback) && !can_draw_over_)
    throw Error(ctx_.caps().name +
                ": swapchain images of this surface cannot be colour attachments and transfer "
                "sources (needed to draw the UI and to read frames back)");
  VkDevice d = ctx_.device();
  uint32_t index = 0;
  VkResult r = vkAcquireNextImageKHR(d, swapchain_, UINT64_MAX, acquired_, VK_NULL_HANDLE, &index);
  if (r == VK_ERROR_OUT_OF_DATE_KHR) {
    needs_recreate_ = true;
    return false;
  }
  if (r == VK_SUBOPTIMAL_KHR)
    needs_recreate_ = true;  // the semaphore is signalled: still present this one
  else
    check(r, "vkAcquireNextImageKHR");

  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  EVF_VK(vkBeginCommandBuffer(cb_, &bi));
  // The pack kernel's writes (an earlier submission) -> this copy's reads.
  VkBufferMemoryBarrier bb{VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER};
  bb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
  bb.dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
  bb.srcQueueFamilyIndex = bb.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  bb.buffer = rgba8.handle();
  bb.offset = 0;
  bb.size = VK_WHOLE_SIZE;
  // Image: whatever it held -> transfer destination. Its stage is the one the acquire
  // semaphore's wait covers, so the layout change happens after the image is ours.
  VkImageMemoryBarrier ib{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
  ib.srcAccessMask = 0;
  ib.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  ib.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  ib.newLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
  ib.srcQueueFamilyIndex = ib.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  ib.image = images_[index];
  ib.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  vkCmdPipelineBarrier(cb_, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                       VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 1, &bb, 1, &ib);
  VkBufferImageCopy region{};
  region.bufferOffset = 0;
  region.bufferRowLength = 0;  // tightly packed
  region.bufferImageHeight = 0;
  region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  region.imageOffset = {0, 0, 0};
  region.imageExtent = {extent_.width, extent_.height, 1};
  vkCmdCopyBufferToImage(cb_, rgba8.handle(), images_[index], VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &region);
  // Where the image is now: layout, and the last stage and access that wrote it.
  Last last{VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT};
  if (draw_over) last = record_draw_over(index, last, draw_over);
  if (readback) last = record_readback(index, last, *readback);
  transition(index, last, {VK_IMAGE_LAYOUT_PRESENT_SRC_KHR, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, 0});
  EVF_VK(vkEndCommandBuffer(cb_));

  const VkPipelineStageFlags wait_stage = VK_PIPELINE_STAGE_TRANSFER_BIT;
  VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  si.waitSemaphoreCount = 1;
  si.pWaitSemaphores = &acquired_;
  si.pWaitDstStageMask = &wait_stage;
  si.commandBufferCount = 1;
  si.pCommandBuffers = &cb_;
  si.signalSemaphoreCount = 1;
  si.pSignalSemaphores = &render_done_[index];
  EVF_VK(vkQueueSubmit(ctx_.queue(), 1, &si, fence_));

  VkPresentInfoKHR pi{VK_STRUCTURE_TYPE_PRESENT_INFO_KHR};
  pi.waitSemaphoreCount = 1;
  pi.pWaitSemaphores = &render_done_[index];
  pi.swapchainCount = 1;
  pi.pSwapchains = &swapchain_;
  pi.pImageIndices = &index;
  VkResult pr = vkQueuePresentKHR(ctx_.queue(), &pi);
  // The copy is done once the fence is: the buffer is free and `acquired_` unsignalled again.
  EVF_VK(vkWaitForFences(d, 1, &fence_, VK_TRUE, UINT64_MAX));
  EVF_VK(vkResetFences(d, 1, &fence_));
  EVF_VK(vkResetCommandBuffer(cb_, 0));
  if (pr == VK_ERROR_OUT_OF_DATE_KHR || pr == VK_SUBOPTIMAL_KHR)
    needs_recreate_ = true;
  else
    check(pr, "vkQueuePresentKHR");
  return true;
}

void Swapchain::transition(uint32_t index, const Last& from, const Last& to) {
  VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
  b.srcAccessMask = from.access;
  b.dstAccessMask = to.access;
  b.oldLayout = from.layout;
  b.newLayout = to.layout;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = images_[index];
  b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  vkCmdPipelineBarrier(cb_, from.stage, to.stage, 0, 0, nullptr, 0, nullptr, 1, &b);
}

Swapchain::Last Swapchain::record_draw_over(uint32_t index, const Last& from, const DrawOver& draw_over) {
  const Last attachment{VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                        VK_ACCESS_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT};
  transition(index, from, attachment);
  VkRenderPassBeginInfo rb{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
  rb.renderPass = render_pass_;
  rb.framebuffer = framebuffers_[index];
  rb.renderArea = {{0, 0}, extent_};
  vkCmdBeginRenderPass(cb_, &rb, VK_SUBPASS_CONTENTS_INLINE);
  draw_over(cb_);
  vkCmdEndRenderPass(cb_);
  return {VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
          VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT};
}

Swapchain::Last Swapchain::record_readback(uint32_t index, const Last& from, const Buffer& dst) {
  transition(index, from,
             {VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT});
  // Earlier readers or writers of the destination (a host read after an earlier fence, compute
  // kernels) -> this copy's write.
  VkBufferMemoryBarrier bb{VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER};
  bb.srcAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_READ_BIT;
  bb.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  bb.srcQueueFamilyIndex = bb.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  bb.buffer = dst.handle();
  bb.size = VK_WHOLE_SIZE;
  vkCmdPipelineBarrier(cb_, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                       VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 1, &bb, 0, nullptr);
  VkBufferImageCopy region{};
  region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  region.imageExtent = {extent_.width, extent_.height, 1};
  vkCmdCopyImageToBuffer(cb_, images_[index], VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, dst.handle(), 1, &region);
  // The copy's write -> the host's read after the fence.
  bb.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  bb.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
  vkCmdPipelineBarrier(cb_, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 0, nullptr, 1, &bb, 0,
                       nullptr);
  return {VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_TRANSFER_BIT, 0};
}

std::string Swapchain::describe() const {
  if (!swapchain_) return "no swapchain (window minimised)";
  return std::to_string(extent_.width) + "x" + std::to_string(extent_.height) + " " + format_name(format_.format) +
         ", " + std::to_string(images_.size()) + " images, " + present_mode_name(mode_);
}

}  // namespace evflow::gpu
