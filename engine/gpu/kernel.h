// A compute pipeline built from an embedded SPIR-V module. Its descriptor set layout (push
// descriptors, storage buffers 0..n-1) is read from the module's Binding decorations; every
// kernel has a 128-byte push-constant range (the Vulkan minimum).
#pragma once
#include <string>

#include "gpu/context.h"

namespace evflow::gpu {

constexpr uint32_t kPushConstantBytes = 128;

class Kernel {
 public:
  Kernel(Context& ctx, const std::string& name);
  ~Kernel();
  Kernel(const Kernel&) = delete;
  Kernel& operator=(const Kernel&) = delete;

  const std::string& name() const { return name_; }
  uint32_t binding_count() const { return bindings_; }
  VkPipeline pipeline() const { return pipeline_; }
  VkPipelineLayout layout() const { return layout_; }

 private:
  Context& ctx_;
  std::string name_;
  uint32_t bindings_ = 0;
  VkShaderModule module_ = VK_NULL_HANDLE;
  VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  VkPipeline pipeline_ = VK_NULL_HANDLE;
};

}  // namespace evflow::gpu
