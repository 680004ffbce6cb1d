// engine/gpu: the only layer that touches raw Vulkan objects.
// Context owns the instance, the chosen device, its compute queue, a command pool and the
// validation messenger. Everything above speaks in Buffer, Kernel and Commands.
#pragma once
#include <vulkan/vulkan.h>

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <unordered_set>
#include <vector>

namespace evflow::gpu {

class Staging;

struct Error : std::runtime_error {
  using std::runtime_error::runtime_error;
};

void check(VkResult r, const char* what);
#define EVF_VK(call) ::evflow::gpu::check((call), #call)

struct ContextOptions {
  // "" = automatic (a GPU when present, else lavapipe); a number = device index;
  // anything else = a case-insensitive substring of the device name.
  std::string device;
  bool validation = false;  // enable VK_LAYER_KHRONOS_validation and collect its messages
  bool poison = false;      // fill fresh buffers with 0xFFFFFFFF (NaN) instead of leaving them
  bool verbose = false;
  bool force_cas = false;         // use the compare-and-swap path even where float atomics exist
  bool print_validation = false;  // also print each validation message to stderr
  // With `validation`: the layer's synchronisation checks (hazards between commands, barriers).
  bool sync_validation = false;
  // With `validation`: GPU-assisted validation (each shader instrumented to report out-of-bounds
  // and uninitialised descriptor accesses). Kernels then bind allocated descriptor sets instead
  // of push descriptors, which the layer's GPU-assisted checks cannot follow.
  bool gpu_validation = false;
  // Kernel choices for the device, overridden where set (Rasterizer, RadixSort read them):
  uint32_t sort_items = 0;    // keys per radix-sort invocation, 1..kSortItemsMax; 0 = by device and size
  int subgroup_reduce = -1;   // rasterize backward: 1 = subgroupAdd first, 0 = per-lane adds; -1 = by device
  std::string raster_kernel;  // "pixel" or "block" compositing kernels; "" = by device
  // A storage binding limit below the device's (bytes; 0: the device's own), and a texel buffer
  // limit of as many 4-byte texels: every size check then answers as a device with those limits
  // would, so the refusals can be tried on any device.
  uint64_t binding_limit = 0;
  // Treat the device as one without host-visible device memory (a discrete GPU): buffers are not
  // mapped and every upload and download goes through the staging copy, as there.
  bool staged_transfers = false;
  // A GPU timestamp after every dispatch: each submit's time per kernel goes to
  // Context::take_kernel_times (evflow bench --kernels). Stage times stay as they are.
  bool kernel_times = false;
  // Presentation (opt-in, for a window): enables these instance extensions (the windowing
  // system's surface extensions, e.g. from glfwGetRequiredInstanceExtensions) plus
  // VK_KHR_surface, and VK_KHR_swapchain on the device; devices without it are skipped.
  bool presentation = false;
  std::vector<std::string> instance_extensions;
  // Defaults that read the environment, once: EVF_DEVICE, EVF_VALIDATION=1, EVF_POISON=1,
  // EVF_FORCE_CAS=1, EVF_VALIDATION_PRINT=1, EVF_VALIDATION_SYNC=1, EVF_VALIDATION_GPU=1,
  // EVF_SORT_ITEMS=n,
  // EVF_SUBGROUP_REDUCE=0|1, EVF_RASTER_KERNEL=pixel|block, EVF_BINDING_LIMIT=bytes, EVF_STAGED=1.
  static ContextOptions from_env();
};

struct DeviceCaps {
  std::string name;
  uint32_t api_version = 0;
  VkPhysicalDeviceType type = VK_PHYSICAL_DEVICE_TYPE_OTHER;
  bool cpu_driver = false;  // a CPU implementation (lavapipe): kernels pick their CPU variants
  uint32_t subgroup_size = 0;
  uint32_t max_workgroup_count[3] = {0, 0, 0};
  uint32_t max_workgroup_invocations = 0;
  uint32_t max_shared_memory = 0;
  uint64_t max_storage_buffer_range = 0;
  uint64_t max_allocation_size = 0;
  uint64_t min_storage_offset_alignment = 0;
  uint64_t max_texel_buffer_elements = 0;  // texels one uniform texel buffer view may span
  uint64_t min_texel_offset_alignment = 0;
  // Bindings one kernel may have: in all (push descriptors), storage buffers, uniform texel
  // buffers (counted as sampled images), and all resources of the stage.
  uint32_t max_push_descriptors = 0;
  uint32_t max_stage_storage_buffers = 0;
  uint32_t max_stage_texel_buffers = 0;
  uint32_t max_stage_resources = 0;
  // Whether a kernel with that many storage buffers and uniform texel buffers can be bound.
  bool fits_bindings(uint32_t storage, uint32_t texel) const {
    return storage <= max_stage_storage_buffers && texel <= max_stage_texel_buffers &&
           storage + texel <= max_stage_resources && storage + texel <= max_push_descriptors;
  }
  bool shared_float_atomic_add = false;
  bool buffer_float_atomic_add = false;
  bool subgroup_arithmetic = false;
  bool timestamps = false;
  double timestamp_period_ns = 1.0;
  bool unified_memory = false;    // every device-local heap is host-visible (lavapipe, iGPUs)
  bool host_query_reset = false;  // vkResetQueryPool from the host (Vulkan 1.2 feature)
};

class Kernel;

class Context {
 public:
  explicit Context(const ContextOptions& opts = ContextOptions::from_env());
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  static std::vector<std::string> list_devices();

  const DeviceCaps& caps() const { return caps_; }
  const ContextOptions& options() const { return opts_; }
  VkInstance instance() const { return instance_; }
  VkDevice device() const { return device_; }
  VkPhysicalDevice physical() const { return physical_; }
  VkQueue queue() const { return queue_; }
  uint32_t queue_family() const { return queue_family_; }
  VkCommandPool command_pool() const { return pool_; }
  // vkCmdPushDescriptorSetKHR of this context's device (loaded when the device is created).
  PFN_vkCmdPushDescriptorSetKHR push_descriptor_set() const { return push_descriptor_set_; }
  // Whether the validation layer instruments every shader (GPU-assisted validation).
  bool gpu_assisted_validation() const { return opts_.validation && opts_.gpu_validation; }
  // Whether kernels bind allocated descriptor sets (GPU-assisted validation) instead of push
  // descriptors.
  bool bound_descriptor_sets() const { return gpu_assisted_validation(); }

  // Whether the compute queue family can present to `surface` (presentation contexts only);
  // require_present throws a clear error naming the device when it cannot.
  bool can_present(VkSurfaceKHR surface) const;
  void require_present(VkSurfaceKHR surface) const;

  // Memory type index with the required flags (and preferred ones when possible).
  uint32_t memory_type(uint32_t type_bits, VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred) const;

  // Kernels are created once per context and cached by embedded name ("splat/project").
  const Kernel& kernel(const std::string& name);
  // The module made for `name` when the context was created (GPU-assisted validation only:
  // create_embedded_modules), handed over to its kernel; VK_NULL_HANDLE where there is none.
  VkShaderModule take_module(const std::string& name);

  // Validation messages (warnings and errors) seen since the last call.
  std::vector<std::string> take_validation_messages();
  size_t validation_message_count() const;
  void report_validation(const std::string& msg);

  // Device memory held by this context's buffers (bytes), now and at most so far. Buffers report
  // their allocations here; the transient staging copies of non-unified devices are not counted.
  void count_allocation(int64_t bytes);
  uint64_t device_bytes() const { return device_bytes_.load(); }
  uint64_t peak_device_bytes() const { return peak_device_bytes_.load(); }

  // Every allocation of a buffer gets a serial that lives until the buffer is released or grown,
  // so that commands can check, when submitted, that nothing they use was freed after recording.
  uint64_t register_allocation();
  void release_allocation(uint64_t serial);
  bool allocation_live(uint64_t serial) const;

  // A primary command buffer from the context's pool, and an unsignalled fence (the caller frees
  // both). submit_and_wait submits `cb`, waits on `fence`, resets it and counts the submit.
  VkCommandBuffer allocate_command_buffer() const;
  VkFence create_fence() const;
  void submit_and_wait(VkCommandBuffer cb, VkFence fence);

  // The staging copy of a device without host-visible device memory (made on first use).
  Staging& staging();

  // Queue submits (commands and staging copies) and host-device copies so far: each is a round
  // trip from the host to the device and back, the cost a GPU pays per step beyond its kernels.
  void count_submit() { submits_.fetch_add(1, std::memory_order_relaxed); }
  void count_transfer() { transfers_.fetch_add(1, std::memory_order_relaxed); }
  uint64_t submits() const { return submits_.load(); }
  uint64_t transfers() const { return transfers_.load(); }

  // Throws a clear error when a binding of `bytes` would exceed the device's storage range.
  void check_binding_size(uint64_t bytes, const std::string& what) const;

  // With ContextOptions::kernel_times: every dispatch's GPU time (ms, by kernel name) that this
  // context's command buffers ran since the last call, in submit and recording order.
  void add_kernel_times(const std::vector<std::pair<std::string, double>>& times);
  std::vector<std::pair<std::string, double>> take_kernel_times();

 private:
  // The steps of construction, in order.
  void create_instance();
  VkPhysicalDeviceProperties choose_device();
  void query_caps(const VkPhysicalDeviceProperties& props);
  void create_device();

  ContextOptions opts_;
  DeviceCaps caps_;
  std::vector<std::pair<std::string, double>> kernel_times_;
  VkInstance instance_ = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  uint32_t queue_family_ = 0;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  PFN_vkCmdPushDescriptorSetKHR push_descriptor_set_ = nullptr;
  VkPhysicalDeviceMemoryProperties mem_props_{};
  std::map<std::string, std::unique_ptr<Kernel>> kernels_;
  std::map<std::string, VkShaderModule> modules_;  // not yet taken by a kernel
  mutable std::mutex msg_mutex_;
  std::vector<std::string> messages_;
  size_t message_total_ = 0;
  std::atomic<uint64_t> device_bytes_{0}, peak_device_bytes_{0};
  std::atomic<uint64_t> submits_{0}, transfers_{0};
  std::mutex staging_mutex_;
  std::unique_ptr<Staging> staging_;
  mutable std::mutex live_mutex_;
  std::unordered_set<uint64_t> live_allocations_;
  uint64_t next_serial_ = 1;
};

}  // namespace evflow::gpu
