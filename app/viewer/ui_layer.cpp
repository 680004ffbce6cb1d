#include "viewer/ui_layer.h"

#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_vulkan.h>

#include <algorithm>
#include <stdexcept>

namespace evflow::viewer {

namespace {

void check_vk(VkResult r) {
  if (r < 0) gpu::check(r, "Dear ImGui's Vulkan backend");
}

bool queue_has_graphics(const gpu::Context& ctx) {
  uint32_t n = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(ctx.physical(), &n, nullptr);
  std::vector<VkQueueFamilyProperties> q(n);
  vkGetPhysicalDeviceQueueFamilyProperties(ctx.physical(), &n, q.data());
  return ctx.queue_family() < n && (q[ctx.queue_family()].queueFlags & VK_QUEUE_GRAPHICS_BIT);
}

VkDescriptorPool make_pool(VkDevice d) {
  // The backend allocates one combined image sampler: the font atlas.
  VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 4};
  VkDescriptorPoolCreateInfo ci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  ci.flags = VK_DESCRIPTOR_POOL_CREATE_FREE_DESCRIPTOR_SET_BIT;
  ci.maxSets = 4;
  ci.poolSizeCount = 1;
  ci.pPoolSizes = &size;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  EVF_VK(vkCreateDescriptorPool(d, &ci, nullptr, &pool));
  return pool;
}

// Records the font atlas upload into a one-off command buffer, submits it and waits.
void upload_fonts(gpu::Context& ctx) {
  VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  ai.commandPool = ctx.command_pool();
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = 1;
  VkCommandBuffer cb = VK_NULL_HANDLE;
  EVF_VK(vkAllocateCommandBuffers(ctx.device(), &ai, &cb));
  VkFence fence = VK_NULL_HANDLE;
  VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  EVF_VK(vkCreateFence(ctx.device(), &fci, nullptr, &fence));
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  EVF_VK(vkBeginCommandBuffer(cb, &bi));
  const bool ok = ImGui_ImplVulkan_CreateFontsTexture(cb);
  EVF_VK(vkEndCommandBuffer(cb));
  VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  si.commandBufferCount = 1;
  si.pCommandBuffers = &cb;
  EVF_VK(vkQueueSubmit(ctx.queue(), 1, &si, fence));
  EVF_VK(vkWaitForFences(ctx.device(), 1, &fence, VK_TRUE, UINT64_MAX));
  vkDestroyFence(ctx.device(), fence, nullptr);
  vkFreeCommandBuffers(ctx.device(), ctx.command_pool(), 1, &cb);
  ImGui_ImplVulkan_DestroyFontUploadObjects();
  if (!ok) throw std::runtime_error("Dear ImGui: the font atlas upload failed");
}

}  // namespace

UiLayer::UiLayer(Display& display) : display_(display) {
  gpu::Context& ctx = display.context();
  gpu::Swapchain& sc = display.swapchain();
  if (!queue_has_graphics(ctx))
    throw std::runtime_error(ctx.caps().name + ": the viewer's queue cannot run graphics (the UI needs it)");
  if (!sc.render_pass()) throw std::runtime_error("the window's swapchain cannot draw the UI over frames");
  imgui_ = ImGui::CreateContext();
  try {
    ImGuiIO& io = ImGui::GetIO();
    io.IniFilename = nullptr;  // no imgui.ini in the working folder
    ImGui::StyleColorsDark();
    ImGui::GetStyle().Alpha = 1.0f;
    glfw_ready_ = ImGui_ImplGlfw_InitForVulkan(display.window(), true);
    if (!glfw_ready_) throw std::runtime_error("Dear ImGui: the GLFW backend did not initialise");
    pool_ = make_pool(ctx.device());
    ImGui_ImplVulkan_InitInfo info{};
    info.Instance = ctx.instance();
    info.PhysicalDevice = ctx.physical();
    info.Device = ctx.device();
    info.QueueFamily = ctx.queue_family();
    info.Queue = ctx.queue();
    info.DescriptorPool = pool_;
    info.Subpass = 0;
    info.MinImageCount = sc.min_image_count();
    info.ImageCount = std::max(sc.image_count(), sc.min_image_count());
    info.MSAASamples = VK_SAMPLE_COUNT_1_BIT;
    info.CheckVkResultFn = check_vk;
    vulkan_ready_ = ImGui_ImplVulkan_Init(&info, sc.render_pass());
    if (!vulkan_ready_) throw std::runtime_error("Dear ImGui: the Vulkan backend did not initialise");
    upload_fonts(ctx);
  } catch (...) {
    shutdown();
    throw;
  }
}

UiLayer::~UiLayer() { shutdown(); }

void UiLayer::shutdown() {
  if (!imgui_) return;
  VkDevice d = display_.context().device();
  vkDeviceWaitIdle(d);
  if (vulkan_ready_) ImGui_ImplVulkan_Shutdown();
  if (glfw_ready_) ImGui_ImplGlfw_Shutdown();
  vulkan_ready_ = glfw_ready_ = false;
  if (pool_) vkDestroyDescriptorPool(d, pool_, nullptr);
  pool_ = VK_NULL_HANDLE;
  ImGui::DestroyContext(imgui_);
  imgui_ = nullptr;
}

void UiLayer::begin() {
  ImGui_ImplVulkan_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGuiIO& io = ImGui::GetIO();
  io.DeltaTime = std::max(io.DeltaTime, 1e-4f);  // frames drawn within one clock tick
  if (scripted_) {
    io.MousePos = ImVec2(px_, py_);
    for (bool& b : io.MouseDown) b = false;
    io.MouseDown[0] = down_;
  }
  ImGui::NewFrame();
}

void UiLayer::end() { ImGui::Render(); }
void UiLayer::discard() { ImGui::EndFrame(); }

void UiLayer::draw(VkCommandBuffer cb) {
  ImDrawData* dd = ImGui::GetDrawData();
  if (dd) ImGui_ImplVulkan_RenderDrawData(dd, cb);
}

// ImGui's sliders keep a 2-pixel padding at both ends and map the value to the grab centre's
// travel between them.
constexpr float kSliderPad = 2.0f;

float UiRect::press_x(double f) const {
  if (f < 0) return x + 0.5f * w;
  return x + kSliderPad + 0.5f * grab + float(f) * (w - 2 * kSliderPad - grab);
}

float UiLayer::slider_grab(float width, int steps) {
  const float min_grab = ImGui::GetStyle().GrabMinSize;
  if (steps <= 0) return min_grab;
  return std::max((width - 2 * kSliderPad) / float(steps + 1), min_grab);
}

void UiLayer::track(const std::string& name, float grab) {
  const ImVec2 a = ImGui::GetItemRectMin(), b = ImGui::GetItemRectMax();
  widgets_[name] = {a.x, a.y, b.x - a.x, b.y - a.y, grab};
}

void UiLayer::track_window(const std::string& name) {
  const ImVec2 p = ImGui::GetWindowPos(), s = ImGui::GetWindowSize();
  widgets_[name] = {p.x, p.y, s.x, s.y, 0};
}

void UiLayer::script_pointer(float x, float y, bool down) {
  scripted_ = true;
  px_ = x;
  py_ = y;
  down_ = down;
}

bool UiLayer::wants_mouse() const { return ImGui::GetIO().WantCaptureMouse; }
bool UiLayer::wants_keys() const { return ImGui::GetIO().WantCaptureKeyboard; }
float UiLayer::font_size() const { return ImGui::GetIO().Fonts->Fonts[0]->FontSize; }

}  // namespace evflow::viewer
