// A window surface's swapchain: the presentation half of the GPU layer (docs/viewer.md).
// The surface is made outside (the windowing library knows how) and handed over; Swapchain
// owns it from then on. Frames are presented by copying a packed RGBA8 buffer (made by the
// kernel "view/pack_rgba8") into the acquired image with vkCmdCopyBufferToImage; a caller may
// then draw over the copied image in one graphics render pass (the viewer's UI), and may have
// the finished image read back into a buffer (screenshots with the UI).
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "gpu/buffer.h"
#include "gpu/context.h"

namespace evflow::gpu {

struct SwapchainSupport {
  VkSurfaceCapabilitiesKHR caps{};
  std::vector<VkSurfaceFormatKHR> formats;
  std::vector<VkPresentModeKHR> present_modes;
};

const char* present_mode_name(VkPresentModeKHR m);

class Swapchain {
 public:
  // Takes ownership of `surface` (created on ctx.instance(); ctx must have presentation on).
  // `vsync` picks FIFO; otherwise MAILBOX, then IMMEDIATE, then FIFO, as supported.
  Swapchain(Context& ctx, VkSurfaceKHR surface, uint32_t width, uint32_t height, bool vsync = false);
  ~Swapchain();
  Swapchain(const Swapchain&) = delete;
  Swapchain& operator=(const Swapchain&) = delete;

  static SwapchainSupport query(const Context& ctx, VkSurfaceKHR surface);

  // Rebuilds the swapchain for a new window size (framebuffer pixels). A 0 x 0 size (a
  // minimised window) is remembered and nothing is built until a real size comes.
  void recreate(uint32_t width, uint32_t height);

  // Presents `rgba8` (width()*height() packed pixels, rows top to bottom, byte order as
  // bgr() says) to the next image. Waits until the copy finished, so the buffer may be
  // rewritten as soon as this returns. Returns false (nothing shown) when the swapchain is out
  // of date or has no images. When needs_recreate() is true afterwards (out of date or
  // suboptimal), the caller calls recreate() with the window's size.
  //
  // `draw_over`, when set, records graphics commands inside render_pass() on the acquired
  // image (its contents loaded: the copied frame). `readback`, when set, receives the finished
  // image (with what draw_over drew) as packed pixels in the same layout as `rgba8`.
  using DrawOver = std::function<void(VkCommandBuffer)>;
  bool present(const Buffer& rgba8, const DrawOver& draw_over = {}, Buffer* readback = nullptr);
  bool needs_recreate() const { return needs_recreate_; }

  bool ready() const { return swapchain_ != VK_NULL_HANDLE; }
  uint32_t width() const { return extent_.width; }
  uint32_t height() const { return extent_.height; }
  // True when the images are B8G8R8A8 (pack with bgr = 1), false for R8G8B8A8.
  bool bgr() const { return bgr_; }
  std::string describe() const;
  // One colour attachment in the swapchain's format, contents loaded, layout
  // COLOR_ATTACHMENT_OPTIMAL before and after: for pipelines that draw over the frame.
  VkRenderPass render_pass() const { return render_pass_; }
  uint32_t image_count() const { return uint32_t(images_.size()); }
  uint32_t min_image_count() const { return min_images_; }

 private:
  void build(uint32_t width, uint32_t height);
  void destroy_swapchain(VkSwapchainKHR sc);
  void cleanup();
  void make_render_pass();
  void make_framebuffers();
  // An image's layout with the stage and access of its last use (or the next one).
  struct Last {
    VkImageLayout layout;
    VkPipelineStageFlags stage;
    VkAccessFlags access;
  };
  void transition(uint32_t index, const Last& from, const Last& to);
  Last record_draw_over(uint32_t index, const Last& from, const DrawOver& draw_over);
  Last record_readback(uint32_t index, const Last& from, const Buffer& dst);
  Context& ctx_;
  VkSurfaceKHR surface_ = VK_NULL_HANDLE;
  VkSwapchainKHR swapchain_ = VK_NULL_HANDLE;
  VkSurfaceFormatKHR format_{};
  VkPresentModeKHR mode_ = VK_PRESENT_MODE_FIFO_KHR;
  VkExtent2D extent_{0, 0};
  bool vsync_ = false;
  bool bgr_ = false;
  bool needs_recreate_ = false;
  uint32_t min_images_ = 2;
  std::vector<VkImage> images_;
  std::vector<VkImageView> views_;
  std::vector<VkFramebuffer> framebuffers_;
  VkRenderPass render_pass_ = VK_NULL_HANDLE;
  VkFormat rp_format_ = VK_FORMAT_UNDEFINED;  // the render pass's format
  bool can_draw_over_ = false;
  std::vector<VkSemaphore> render_done_;   // one per image: signalled by the copy, waited by present
  VkSemaphore acquired_ = VK_NULL_HANDLE;  // the copy waits on it (free again after the fence wait)
  VkFence fence_ = VK_NULL_HANDLE;
  VkCommandBuffer cb_ = VK_NULL_HANDLE;
};

}  // namespace evflow::gpu
