// A compute pipeline built from an embedded SPIR-V module. Its descriptor set layout (push
// descriptors, or allocated sets under GPU-assisted validation) is read from the module: each
// variable's Binding decoration and the name of its block type (glslang keeps names). A binding
// is a storage buffer, or, for a `samplerBuffer` / `usamplerBuffer` / `isamplerBuffer` variable,
// a uniform texel buffer named by the variable, viewed as RGBA32F / R32UI / R32I texels. Every
// kernel has a 128-byte push-constant range (the Vulkan minimum).
#pragma once
#include <map>
#include <string>
#include <vector>

#include "gpu/context.h"

namespace evflow::gpu {

constexpr uint32_t kPushConstantBytes = 128;

// Every embedded shader's module, created in the registry's order: with GPU-assisted validation
// the layer numbers each module it instruments in the order of creation and builds the number
// into the module, so a kernel's instrumented code, and the driver's cached compile of it, are
// the same in every process only when every process creates the modules in one order
// (Context::Context does so under GPU-assisted validation; docs/robustness.md).
std::map<std::string, VkShaderModule> create_embedded_modules(VkDevice device);

class Kernel {
 public:
  Kernel(Context& ctx, const std::string& name);
  ~Kernel();
  Kernel(const Kernel&) = delete;
  Kernel& operator=(const Kernel&) = delete;

  struct Binding {
    uint32_t index;
    std::string block;                            // the block type's name in the SPIR-V ("" where it has none)
    VkFormat texel_format = VK_FORMAT_UNDEFINED;  // a uniform texel buffer's view; UNDEFINED: storage
  };

  const std::string& name() const { return name_; }
  // The buffer bindings the module declares (and its optimiser kept), by index.
  const std::vector<Binding>& bindings() const { return bindings_; }
  VkPipeline pipeline() const { return pipeline_; }
  VkPipelineLayout layout() const { return layout_; }
  VkDescriptorSetLayout set_layout() const { return set_layout_; }

 private:
  Context& ctx_;
  std::string name_;
  std::vector<Binding> bindings_;
  VkShaderModule module_ = VK_NULL_HANDLE;
  VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  VkPipeline pipeline_ = VK_NULL_HANDLE;
};

}  // namespace evflow::gpu
