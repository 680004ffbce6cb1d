#include "gpu/kernel.h"

#include <algorithm>
#include <cstring>
#include <map>
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

// The bindings of a module: variables decorated with Binding, named by their block type (the
// pointee of the variable's pointer type), or, for a buffer texture (a sampled image of dimension
// Buffer), by the variable itself, with its view format from the sampled type. Opcodes: OpName 5,
// OpTypeInt 21, OpTypeFloat 22, OpTypeImage 25, OpTypeSampledImage 27, OpTypePointer 32,
// OpVariable 59, OpDecorate 71; decoration Binding 33; dimension Buffer 5.
static std::vector<Kernel::Binding> reflect_bindings(const uint32_t* w, size_t n_words) {
  std::map<uint32_t, std::string> names;
  std::map<uint32_t, uint32_t> pointee, var_type, binding_of, sampled_image;
  std::map<uint32_t, VkFormat> texel_format_of_image, format_of_scalar;
  for (size_t i = 5; i < n_words;) {
    const uint32_t op = w[i] & 0xFFFF, len = w[i] >> 16;
    if (len == 0 || i + len > n_words) break;
    if (op == 5 && len >= 3) {
      const char* c = reinterpret_cast<const char*>(&w[i + 2]);
      names[w[i + 1]] = std::string(c, strnlen(c, (len - 2) * 4));
    } else if (op == 21 && len >= 4) {
      format_of_scalar[w[i + 1]] = w[i + 3] ? VK_FORMAT_R32_SINT : VK_FORMAT_R32_UINT;
    } else if (op == 22 && len >= 3) {
      format_of_scalar[w[i + 1]] = VK_FORMAT_R32G32B32A32_SFLOAT;
    } else if (op == 25 && len >= 9 && w[i + 3] == 5) {
      auto f = format_of_scalar.find(w[i + 2]);
      if (f != format_of_scalar.end()) texel_format_of_image[w[i + 1]] = f->second;
    } else if (op == 27 && len >= 3) {
      sampled_image[w[i + 1]] = w[i + 2];
    } else if (op == 32 && len >= 4) {
      pointee[w[i + 1]] = w[i + 3];
    } else if (op == 59 && len >= 4) {
      var_type[w[i + 2]] = w[i + 1];
    } else if (op == 71 && len >= 4 && w[i + 2] == 33) {
      binding_of[w[i + 1]] = w[i + 3];
    }
    i += len;
  }
  std::vector<Kernel::Binding> out;
  for (auto [id, index] : binding_of) {
    Kernel::Binding b{index, "", VK_FORMAT_UNDEFINED};
    auto t = var_type.find(id);
    auto p = t != var_type.end() ? pointee.find(t->second) : pointee.end();
    if (p != pointee.end()) {
      auto img = sampled_image.find(p->second);
      auto texel = img != sampled_image.end() ? texel_format_of_image.find(img->second) : texel_format_of_image.end();
      if (texel != texel_format_of_image.end()) {
        b.texel_format = texel->second;
        if (names.count(id)) b.block = names[id];
      } else if (names.count(p->second)) {
        b.block = names[p->second];
      }
    }
    out.push_back(b);
  }
  std::sort(out.begin(), out.end(),
            [](const Kernel::Binding& a, const Kernel::Binding& b) { return a.index < b.index; });
  return out;
}

static VkShaderModule create_module(VkDevice device, const EmbeddedShader& s) {
  VkShaderModuleCreateInfo smci{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  smci.codeSize = s.bytes;
  smci.pCode = s.words;
  VkShaderModule m = VK_NULL_HANDLE;
  EVF_VK(vkCreateShaderModule(device, &smci, nullptr, &m));
  return m;
}

std::map<std::string, VkShaderModule> create_embedded_modules(VkDevice device) {
  std::map<std::string, VkShaderModule> modules;
  for (const EmbeddedShader* s = kEmbeddedShaders; s->name; ++s) modules[s->name] = create_module(device, *s);
  return modules;
}

Kernel::Kernel(Context& ctx, const std::string& name) : ctx_(ctx), name_(name) {
  const EmbeddedShader* s = find_shader(name);
  if (!s) throw Error("no embedded shader named '" + name + "'");
  bindings_ = reflect_bindings(s->words, s->bytes / 4);
  module_ = ctx.take_module(name);
  if (!module_) module_ = create_module(ctx.device(), *s);

  std::vector<VkDescriptorSetLayoutBinding> binds(bindings_.size());
  for (size_t i = 0; i < bindings_.size(); ++i) {
    binds[i] = {};
    binds[i].binding = bindings_[i].index;
    binds[i].descriptorType = bindings_[i].texel_format == VK_FORMAT_UNDEFINED
                                  ? VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
                                  : VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
    binds[i].descriptorCount = 1;
    binds[i].stageFlags = VK_SHADER_STAGE_COMPUTE_BIT;
  }
  VkDescriptorSetLayoutCreateInfo dci{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  dci.flags = ctx.bound_descriptor_sets() ? 0 : VK_DESCRIPTOR_SET_LAYOUT_CREATE_PUSH_DESCRIPTOR_BIT_KHR;
  dci.bindingCount = static_cast<uint32_t>(binds.size());
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
