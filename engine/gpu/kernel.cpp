#include "gpu/kernel.h"

#include <vector>

namespace evflow::gpu {

struct EmbeddedShader {
  const char* name;
  const uint32_t* words;
  size_t bytes;
};
extern const EmbeddedShader kEmbeddedShaders[];

static const EmbeddedShader* find_shader(const std::string& name) {
  for (const EmbeddedShader* s = kEmbeddedShaders; s->name; ++s)
    if (name == s->name) return s;
  return nullptr;
}

// Highest `Binding` decoration + 1 (OpDecorate = 71, Decoration Binding = 33).
static uint32_t count_bindings(const uint32_t* w, size_t n_words) {
  uint32_t max_binding = 0;
  bool any = false;
  for (size_t i = 5; i < n_words;) {
    uint32_t op = w[i] & 0xFFFF, len = w[i] >> 16;
    if (len == 0) break;
    if (op == 71 && len >= 4 && w[i + 2] == 33) {
      max_binding = std::max(max_binding, w[i + 3]);
      any = true;
    }
    i += len;
  }
  return any ? max_binding + 1 : 0;
}

Kernel::Kernel(Context& ctx, const std::string& name) : ctx_(ctx), name_(name) {
  const EmbeddedShader* s = find_shader(name);
  if (!s) throw Error("no embedded shader named '" + name + "'");
  bindings_ = count_bindings(s->words, s->bytes / 4);
  VkShaderModuleCreateInfo smci{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  smci.codeSize = s->bytes;
  smci.pCode = s->words;
  EVF_VK(vkCreateShaderModule(ctx.device(), &smci, nullptr, &module_));

  std::vector<VkDescriptorSetLayoutBinding> binds(bindings_);
  for (uint32_t i = 0; i < bindings_; ++i) {
    binds[i] = {};
    binds[i].binding = i;
    binds[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    binds[i].descriptorCount = 1;
    binds[i].stageFlags = VK_SHADER_STAGE_COMPUTE_BIT;
  }
  VkDescriptorSetLayoutCreateInfo dci{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  dci.flags = VK_DESCRIPTOR_SET_LAYOUT_CREATE_PUSH_DESCRIPTOR_BIT_KHR;
  dci.bindingCount = bindings_;
  dci.pBindings = binds.data();
  EVF_VK(vkCreateDescriptorSetLayout(ctx.device(), &dci, nullptr, &set_layout_));

  VkPushConstantRange pcr{VK_SHADER_STAGE_COMPUTE_BIT, 0, kPushConstantBytes};
  VkPipelineLayoutCreateInfo lci{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  lci.setLayoutCount = 1;
  lci.pSetLayouts = &set_layout_;
  lci.pushConstantRangeCount = 1;
  lci.pPushConstantRanges = &pcr;
  EVF_VK(vkCreatePipelineLayout(ctx.device(), &lci, nullptr, &layout_));

  VkComputePipelineCreateInfo pci{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
  pci.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
  pci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  pci.stage.module = module_;
  pci.stage.pName = "main";
  pci.layout = layout_;
  EVF_VK(vkCreateComputePipelines(ctx.device(), VK_NULL_HANDLE, 1, &pci, nullptr, &pipeline_));
}

Kernel::~Kernel() {
  VkDevice d = ctx_.device();
  if (pipeline_) vkDestroyPipeline(d, pipeline_, nullptr);
  if (layout_) vkDestroyPipelineLayout(d, layout_, nullptr);
  if (set_layout_) vkDestroyDescriptorSetLayout(d, set_layout_, nullptr);
  if (module_) vkDestroyShaderModule(d, module_, nullptr);
}

}  // namespace evflow::gpu
