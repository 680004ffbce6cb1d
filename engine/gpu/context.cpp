#include "gpu/context.h"

#include "gpu/staging.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <utility>

#include "gpu/kernel.h"
#include "sort/sort_layout.h"

namespace evflow::gpu {

void check(VkResult r, const char* what) {
  if (r != VK_SUCCESS) throw Error(std::string("Vulkan call failed (VkResult ") + std::to_string(r) + "): " + what);
}

static bool env_flag(const char* name) {
  const char* v = std::getenv(name);
  return v && *v && std::strcmp(v, "0") != 0;
}

// The whole number in environment variable `name` (set, with value `text`), from lo to hi, else
// an error naming the variable.
static uint64_t env_whole(const char* name, const char* text, uint64_t lo, uint64_t hi) {
  const bool digits_only = *text != '\0' && std::strspn(text, "0123456789") == std::strlen(text);
  errno = 0;
  const unsigned long long v = digits_only ? std::strtoull(text, nullptr, 10) : 0;
  if (!digits_only || errno == ERANGE || v < lo || v > hi)
    throw Error(std::string(name) + " must be a whole number from " + std::to_string(lo) + " to " + std::to_string(hi) +
                ", not '" + text + "'");
  return v;
}

ContextOptions ContextOptions::from_env() {
  ContextOptions o;
  if (const char* d = std::getenv("EVF_DEVICE")) o.device = d;
  o.validation = env_flag("EVF_VALIDATION");
  o.poison = env_flag("EVF_POISON");
  o.force_cas = env_flag("EVF_FORCE_CAS");
  o.print_validation = env_flag("EVF_VALIDATION_PRINT");
  o.sync_validation = env_flag("EVF_VALIDATION_SYNC");
  o.gpu_validation = env_flag("EVF_VALIDATION_GPU");
  if (const char* e = std::getenv("EVF_SORT_ITEMS"))
    o.sort_items = uint32_t(env_whole("EVF_SORT_ITEMS", e, 1, shaderio::kSortItemsMax));
  if (const char* e = std::getenv("EVF_SUBGROUP_REDUCE")) o.subgroup_reduce = e[0] == '1' ? 1 : 0;
  if (const char* e = std::getenv("EVF_RASTER_KERNEL")) {
    o.raster_kernel = e;
    if (o.raster_kernel != "pixel" && o.raster_kernel != "block")
      throw Error("EVF_RASTER_KERNEL must be 'pixel' or 'block', not '" + o.raster_kernel + "'");
  }
  if (const char* e = std::getenv("EVF_BINDING_LIMIT"))
    o.binding_limit = env_whole("EVF_BINDING_LIMIT", e, 16, std::numeric_limits<uint64_t>::max());
  o.staged_transfers = env_flag("EVF_STAGED");
  return o;
}

static VKAPI_ATTR VkBool32 VKAPI_CALL debug_callback(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                     VkDebugUtilsMessageTypeFlagsEXT,
                                                     const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
  auto* ctx = static_cast<Context*>(user);
  std::string msg =
      (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT) ? "validation error: " : "validation warning: ";
  msg += data->pMessage ? data->pMessage : "(no message)";
  ctx->report_validation(msg);
  return VK_FALSE;
}

static std::string lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

static VkInstance make_instance(bool validation, VkDebugUtilsMessengerCreateInfoEXT* dbg,
                                const std::vector<std::string>& extra_exts = {},
                                const std::vector<VkValidationFeatureEnableEXT>& features = {}) {
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "evflow";
  app.apiVersion = VK_API_VERSION_1_2;
  std::vector<const char*> layers, exts;
  if (validation) {
    uint32_t n = 0;
    vkEnumerateInstanceLayerProperties(&n, nullptr);
    std::vector<VkLayerProperties> props(n);
    vkEnumerateInstanceLayerProperties(&n, props.data());
    bool found = std::any_of(props.begin(), props.end(),
                             [](auto& p) { return std::strcmp(p.layerName, "VK_LAYER_KHRONOS_validation") == 0; });
    if (!found)
      throw Error(
          "validation requested but VK_LAYER_KHRONOS_validation is not installed "
          "(Debian package vulkan-validationlayers)");
    layers.push_back("VK_LAYER_KHRONOS_validation");
    exts.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
    if (!features.empty()) exts.push_back(VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME);
  }
  for (const std::string& e : extra_exts)
    if (std::none_of(exts.begin(), exts.end(), [&](const char* x) { return e == x; })) exts.push_back(e.c_str());
  VkInstanceCreateInfo ci{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ci.pApplicationInfo = &app;
  ci.enabledLayerCount = static_cast<uint32_t>(layers.size());
  ci.ppEnabledLayerNames = layers.data();
  ci.enabledExtensionCount = static_cast<uint32_t>(exts.size());
  ci.ppEnabledExtensionNames = exts.data();
  VkValidationFeaturesEXT vf{VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT};
  vf.enabledValidationFeatureCount = uint32_t(features.size());
  vf.pEnabledValidationFeatures = features.data();
  vf.pNext = dbg;
  if (validation) ci.pNext = features.empty() ? static_cast<const void*>(dbg) : &vf;
  VkInstance inst = VK_NULL_HANDLE;
  VkResult r = vkCreateInstance(&ci, nullptr, &inst);
  if (r == VK_ERROR_INCOMPATIBLE_DRIVER)
    throw Error("no Vulkan driver found: install mesa-vulkan-drivers (lavapipe) or a GPU driver");
  check(r, "vkCreateInstance");
  return inst;
}

static bool has_extension(VkPhysicalDevice pd, const char* name) {
  uint32_t n = 0;
  vkEnumerateDeviceExtensionProperties(pd, nullptr, &n, nullptr);
  std::vector<VkExtensionProperties> props(n);
  vkEnumerateDeviceExtensionProperties(pd, nullptr, &n, props.data());
  return std::any_of(props.begin(), props.end(), [&](auto& p) { return std::strcmp(p.extensionName, name) == 0; });
}

static int compute_family(VkPhysicalDevice pd) {
  uint32_t n = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, nullptr);
  std::vector<VkQueueFamilyProperties> q(n);
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, q.data());
  for (uint32_t i = 0; i < n; ++i)
    if (q[i].queueFlags & VK_QUEUE_COMPUTE_BIT) return static_cast<int>(i);
  return -1;
}

static int type_rank(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
      return 0;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
      return 1;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
      return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU:
      return 3;
    default:
      return 4;
  }
}

std::vector<std::string> Context::list_devices() {
  VkInstance inst = make_instance(false, nullptr);
  uint32_t n = 0;
  vkEnumeratePhysicalDevices(inst, &n, nullptr);
  std::vector<VkPhysicalDevice> pds(n);
  vkEnumeratePhysicalDevices(inst, &n, pds.data());
  std::vector<std::string> out;
  for (uint32_t i = 0; i < n; ++i) {
    VkPhysicalDeviceProperties p;
    vkGetPhysicalDeviceProperties(pds[i], &p);
    out.push_back(std::to_string(i) + ": " + p.deviceName + " (Vulkan " +
                  std::to_string(VK_API_VERSION_MAJOR(p.apiVersion)) + "." +
                  std::to_string(VK_API_VERSION_MINOR(p.apiVersion)) + ")");
  }
  vkDestroyInstance(inst, nullptr);
  return out;
}

Context::Context(const ContextOptions& opts) : opts_(opts) {
  create_instance();
  query_caps(choose_device());
  create_device();
  if (gpu_assisted_validation()) modules_ = create_embedded_modules(device_);
  if (opts_.verbose)
    std::fprintf(stderr, "evflow: device %s, subgroup %u, storage range %llu MiB, shared float atomics %s\n",
                 caps_.name.c_str(), caps_.subgroup_size,
                 static_cast<unsigned long long>(caps_.max_storage_buffer_range >> 20),
                 caps_.shared_float_atomic_add ? "yes" : "no (CAS)");
}

// The instance (with the validation layer and its messenger when asked for).
void Context::create_instance() {
  VkDebugUtilsMessengerCreateInfoEXT dbg{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
  dbg.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  dbg.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                    VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
  dbg.pfnUserCallback = debug_callback;
  dbg.pUserData = this;
  std::vector<std::string> extra_exts;
  if (opts_.presentation) {
    extra_exts.push_back(VK_KHR_SURFACE_EXTENSION_NAME);
    for (const std::string& e : opts_.instance_extensions)
      if (std::find(extra_exts.begin(), extra_exts.end(), e) == extra_exts.end()) extra_exts.push_back(e);
  }
  std::vector<VkValidationFeatureEnableEXT> features;
  if (opts_.sync_validation) features.push_back(VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT);
  if (opts_.gpu_validation) features.push_back(VK_VALIDATION_FEATURE_ENABLE_GPU_ASSISTED_EXT);
  instance_ = make_instance(opts_.validation, &dbg, extra_exts, features);
  if (!opts_.validation) return;
  auto fn = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
      vkGetInstanceProcAddr(instance_, "vkCreateDebugUtilsMessengerEXT"));
  if (!fn) throw Error("vkCreateDebugUtilsMessengerEXT is unavailable");
  EVF_VK(fn(instance_, &dbg, nullptr, &messenger_));
}

// Why a device cannot be used (Vulkan 1.2+, a compute queue, push descriptors, a swapchain for
// presentation), or "" when it can.
static std::string unusable(VkPhysicalDevice pd, const VkPhysicalDeviceProperties& p, bool presentation) {
  if (p.apiVersion < VK_API_VERSION_1_2) return "Vulkan < 1.2";
  if (compute_family(pd) < 0) return "no compute queue";
  if (!has_extension(pd, VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME)) return "no VK_KHR_push_descriptor";
  if (presentation && !has_extension(pd, VK_KHR_SWAPCHAIN_EXTENSION_NAME)) return "no VK_KHR_swapchain";
  return "";
}

// The usable device `opts_.device` names (an index or part of a name), else the most capable type.
VkPhysicalDeviceProperties Context::choose_device() {
  uint32_t n = 0;
  vkEnumeratePhysicalDevices(instance_, &n, nullptr);
  std::vector<VkPhysicalDevice> pds(n);
  vkEnumeratePhysicalDevices(instance_, &n, pds.data());
  std::vector<std::pair<VkPhysicalDevice, VkPhysicalDeviceProperties>> cands;
  std::string rejected;
  for (auto pd : pds) {
    VkPhysicalDeviceProperties p;
    vkGetPhysicalDeviceProperties(pd, &p);
    const std::string why = unusable(pd, p, opts_.presentation);
    if (why.empty())
      cands.emplace_back(pd, p);
    else
      rejected += std::string(" ") + p.deviceName + " (" + why + ");";
  }
  if (cands.empty()) throw Error("no usable Vulkan device (need 1.2+, compute, push descriptors):" + rejected);
  int chosen = -1;
  if (opts_.device.empty()) {
    chosen = 0;
    for (size_t i = 1; i < cands.size(); ++i)
      if (type_rank(cands[i].second.deviceType) < type_rank(cands[chosen].second.deviceType))
        chosen = static_cast<int>(i);
  } else if (std::all_of(opts_.device.begin(), opts_.device.end(), ::isdigit)) {
    const size_t idx = opts_.device.size() > 9 ? cands.size() : std::stoul(opts_.device);  // no wrap, no throw
    if (idx >= cands.size())
      throw Error("--device " + opts_.device + ": only " + std::to_string(cands.size()) + " usable device(s)");
    chosen = static_cast<int>(idx);
  } else {
    for (size_t i = 0; i < cands.size() && chosen < 0; ++i)
      if (lower(cands[i].second.deviceName).find(lower(opts_.device)) != std::string::npos)
        chosen = static_cast<int>(i);
    if (chosen < 0) throw Error("--device '" + opts_.device + "' matches no usable device");
  }
  physical_ = cands[chosen].first;
  queue_family_ = static_cast<uint32_t>(compute_family(physical_));
  return cands[chosen].second;
}

// Limits, subgroups, float atomics and memory types of the chosen device.
void Context::query_caps(const VkPhysicalDeviceProperties& props) {
  VkPhysicalDeviceSubgroupProperties sub{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
  VkPhysicalDeviceMaintenance3Properties m3{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MAINTENANCE_3_PROPERTIES};
  VkPhysicalDevicePushDescriptorPropertiesKHR push{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PUSH_DESCRIPTOR_PROPERTIES_KHR};
  sub.pNext = &m3;
  m3.pNext = &push;
  VkPhysicalDeviceProperties2 p2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
  p2.pNext = &sub;
  vkGetPhysicalDeviceProperties2(physical_, &p2);
  caps_.name = props.deviceName;
  caps_.api_version = props.apiVersion;
  caps_.type = props.deviceType;
  caps_.cpu_driver = props.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
  caps_.subgroup_size = sub.subgroupSize;
  caps_.subgroup_arithmetic = (sub.supportedStages & VK_SHADER_STAGE_COMPUTE_BIT) &&
                              (sub.supportedOperations & VK_SUBGROUP_FEATURE_ARITHMETIC_BIT) &&
                              (sub.supportedOperations & VK_SUBGROUP_FEATURE_BASIC_BIT) &&
                              (sub.supportedOperations & VK_SUBGROUP_FEATURE_VOTE_BIT);
  for (int i = 0; i < 3; ++i) caps_.max_workgroup_count[i] = props.limits.maxComputeWorkGroupCount[i];
  caps_.max_workgroup_invocations = props.limits.maxComputeWorkGroupInvocations;
  caps_.max_shared_memory = props.limits.maxComputeSharedMemorySize;
  caps_.max_storage_buffer_range = props.limits.maxStorageBufferRange;
  if (opts_.binding_limit)
    caps_.max_storage_buffer_range = std::min<uint64_t>(caps_.max_storage_buffer_range, opts_.binding_limit);
  caps_.min_storage_offset_alignment = props.limits.minStorageBufferOffsetAlignment;
  caps_.max_texel_buffer_elements = props.limits.maxTexelBufferElements;
  if (opts_.binding_limit)
    caps_.max_texel_buffer_elements = std::min<uint64_t>(caps_.max_texel_buffer_elements, opts_.binding_limit / 4);
  caps_.min_texel_offset_alignment = props.limits.minTexelBufferOffsetAlignment;
  caps_.timestamps = props.limits.timestampComputeAndGraphics;
  caps_.timestamp_period_ns = props.limits.timestampPeriod;
  caps_.max_allocation_size = m3.maxMemoryAllocationSize;
  caps_.max_push_descriptors = push.maxPushDescriptors;
  caps_.max_stage_storage_buffers = props.limits.maxPerStageDescriptorStorageBuffers;
  caps_.max_stage_texel_buffers = props.limits.maxPerStageDescriptorSampledImages;
  caps_.max_stage_resources = props.limits.maxPerStageResources;
  if (!caps_.subgroup_arithmetic)
    throw Error(caps_.name +
                ": subgroup basic, vote and arithmetic operations in compute shaders are required and missing");
  const bool has_atomic_float = has_extension(physical_, VK_EXT_SHADER_ATOMIC_FLOAT_EXTENSION_NAME);
  VkPhysicalDeviceShaderAtomicFloatFeaturesEXT af{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SHADER_ATOMIC_FLOAT_FEATURES_EXT};
  VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
  VkPhysicalDeviceFeatures2 f2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
  f2.pNext = &f12;
  if (has_atomic_float) f12.pNext = &af;
  vkGetPhysicalDeviceFeatures2(physical_, &f2);
  caps_.host_query_reset = f12.hostQueryReset;
  // The splat kernels read and write packed [N][3] rows as vec3 arrays of 12-byte stride.
  if (!f12.scalarBlockLayout)
    throw Error(caps_.name + ": the scalar block layout (Vulkan 1.2) is required and missing");
  caps_.shared_float_atomic_add = has_atomic_float && af.shaderSharedFloat32AtomicAdd && !opts_.force_cas;
  caps_.buffer_float_atomic_add = has_atomic_float && af.shaderBufferFloat32AtomicAdd && !opts_.force_cas;
  vkGetPhysicalDeviceMemoryProperties(physical_, &mem_props_);
  caps_.unified_memory = true;
  for (uint32_t i = 0; i < mem_props_.memoryTypeCount; ++i) {
    auto f = mem_props_.memoryTypes[i].propertyFlags;
    if ((f & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT) && !(f & VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT))
      caps_.unified_memory = false;
  }
  if (opts_.staged_transfers) caps_.unified_memory = false;
}

// The device with only the features used, its queue and command pool.
void Context::create_device() {
  VkPhysicalDeviceShaderAtomicFloatFeaturesEXT af_on{
      VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SHADER_ATOMIC_FLOAT_FEATURES_EXT};
  af_on.shaderSharedFloat32AtomicAdd = caps_.shared_float_atomic_add;
  af_on.shaderBufferFloat32AtomicAdd = caps_.buffer_float_atomic_add;
  VkPhysicalDeviceVulkan12Features f12_on{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
  f12_on.hostQueryReset = caps_.host_query_reset;
  f12_on.scalarBlockLayout = VK_TRUE;
  if (af_on.shaderSharedFloat32AtomicAdd || af_on.shaderBufferFloat32AtomicAdd) f12_on.pNext = &af_on;
  VkPhysicalDeviceFeatures2 f2_on{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
  f2_on.pNext = &f12_on;
  std::vector<const char*> dev_exts = {VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME};
  if (f12_on.pNext) dev_exts.push_back(VK_EXT_SHADER_ATOMIC_FLOAT_EXTENSION_NAME);
  if (opts_.presentation) dev_exts.push_back(VK_KHR_SWAPCHAIN_EXTENSION_NAME);
  float prio = 1.0f;
  VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  qci.queueFamilyIndex = queue_family_;
  qci.queueCount = 1;
  qci.pQueuePriorities = &prio;
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  dci.pNext = &f2_on;
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &qci;
  dci.enabledExtensionCount = static_cast<uint32_t>(dev_exts.size());
  dci.ppEnabledExtensionNames = dev_exts.data();
  EVF_VK(vkCreateDevice(physical_, &dci, nullptr, &device_));
  vkGetDeviceQueue(device_, queue_family_, 0, &queue_);
  push_descriptor_set_ =
      reinterpret_cast<PFN_vkCmdPushDescriptorSetKHR>(vkGetDeviceProcAddr(device_, "vkCmdPushDescriptorSetKHR"));
  VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pci.queueFamilyIndex = queue_family_;
  EVF_VK(vkCreateCommandPool(device_, &pci, nullptr, &pool_));
}

Context::~Context() {
  if (device_) vkDeviceWaitIdle(device_);
  kernels_.clear();
  for (auto& [name, m] : modules_) vkDestroyShaderModule(device_, m, nullptr);
  staging_.reset();
  if (pool_) vkDestroyCommandPool(device_, pool_, nullptr);
  if (device_) vkDestroyDevice(device_, nullptr);
  if (messenger_) {
    auto fn = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
    if (fn) fn(instance_, messenger_, nullptr);
  }
  if (instance_) vkDestroyInstance(instance_, nullptr);
}

VkCommandBuffer Context::allocate_command_buffer() const {
  VkCommandBufferAllocateInfo cai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  cai.commandPool = pool_;
  cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  cai.commandBufferCount = 1;
  VkCommandBuffer cb;
  EVF_VK(vkAllocateCommandBuffers(device_, &cai, &cb));
  return cb;
}

VkFence Context::create_fence() const {
  VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  VkFence fence;
  EVF_VK(vkCreateFence(device_, &fci, nullptr, &fence));
  return fence;
}

void Context::submit_and_wait(VkCommandBuffer cb, VkFence fence) {
  VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  si.commandBufferCount = 1;
  si.pCommandBuffers = &cb;
  count_submit();
  EVF_VK(vkQueueSubmit(queue_, 1, &si, fence));
  EVF_VK(vkWaitForFences(device_, 1, &fence, VK_TRUE, UINT64_MAX));
  EVF_VK(vkResetFences(device_, 1, &fence));
}

Staging& Context::staging() {
  std::lock_guard<std::mutex> lock(staging_mutex_);
  if (!staging_) staging_ = std::make_unique<Staging>(*this);
  return *staging_;
}

bool Context::can_present(VkSurfaceKHR surface) const {
  if (!opts_.presentation) return false;
  VkBool32 ok = VK_FALSE;
  EVF_VK(vkGetPhysicalDeviceSurfaceSupportKHR(physical_, queue_family_, surface, &ok));
  return ok == VK_TRUE;
}

void Context::require_present(VkSurfaceKHR surface) const {
  if (!opts_.presentation) throw Error("presenting needs a context created with ContextOptions::presentation");
  if (!can_present(surface))
    throw Error(caps_.name + ": its compute queue family " + std::to_string(queue_family_) +
                " cannot present to this window's surface");
}

uint32_t Context::memory_type(uint32_t bits, VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred) const {
  int fallback = -1;
  for (uint32_t i = 0; i < mem_props_.memoryTypeCount; ++i) {
    if (!(bits & (1u << i))) continue;
    auto f = mem_props_.memoryTypes[i].propertyFlags;
    if ((f & required) != required) continue;
    if ((f & preferred) == preferred) return i;
    if (fallback < 0) fallback = static_cast<int>(i);
  }
  if (fallback < 0) throw Error("no Vulkan memory type with the required properties");
  return static_cast<uint32_t>(fallback);
}

const Kernel& Context::kernel(const std::string& name) {
  auto it = kernels_.find(name);
  if (it != kernels_.end()) return *it->second;
  auto k = std::make_unique<Kernel>(*this, name);
  auto& ref = *k;
  kernels_[name] = std::move(k);
  return ref;
}

VkShaderModule Context::take_module(const std::string& name) {
  auto it = modules_.find(name);
  if (it == modules_.end()) return VK_NULL_HANDLE;
  VkShaderModule m = it->second;
  modules_.erase(it);
  return m;
}

void Context::report_validation(const std::string& msg) {
  std::lock_guard<std::mutex> lock(msg_mutex_);
  messages_.push_back(msg);
  ++message_total_;
  if (opts_.verbose || opts_.print_validation) std::fprintf(stderr, "%s\n", msg.c_str());
}

std::vector<std::string> Context::take_validation_messages() {
  std::lock_guard<std::mutex> lock(msg_mutex_);
  std::vector<std::string> out;
  out.swap(messages_);
  return out;
}

size_t Context::validation_message_count() const {
  std::lock_guard<std::mutex> lock(msg_mutex_);
  return message_total_;
}

void Context::count_allocation(int64_t bytes) {
  const uint64_t now = device_bytes_.fetch_add(uint64_t(bytes)) + uint64_t(bytes);
  uint64_t peak = peak_device_bytes_.load();
  while (now > peak && !peak_device_bytes_.compare_exchange_weak(peak, now)) {}
}

uint64_t Context::register_allocation() {
  std::lock_guard<std::mutex> lock(live_mutex_);
  live_allocations_.insert(next_serial_);
  return next_serial_++;
}

void Context::release_allocation(uint64_t serial) {
  std::lock_guard<std::mutex> lock(live_mutex_);
  live_allocations_.erase(serial);
}

bool Context::allocation_live(uint64_t serial) const {
  std::lock_guard<std::mutex> lock(live_mutex_);
  return live_allocations_.count(serial) != 0;
}

void Context::check_binding_size(uint64_t bytes, const std::string& what) const {
  if (bytes > caps_.max_storage_buffer_range)
    throw Error(what + " needs a " + std::to_string(bytes) +
                "-byte storage binding, above this device's maxStorageBufferRange of " +
                std::to_string(caps_.max_storage_buffer_range) + " bytes (" + caps_.name + ")");
}

void Context::add_kernel_times(const std::vector<std::pair<std::string, double>>& times) {
  kernel_times_.insert(kernel_times_.end(), times.begin(), times.end());
}

std::vector<std::pair<std::string, double>> Context::take_kernel_times() { return std::exchange(kernel_times_, {}); }

}  // namespace evflow::gpu
