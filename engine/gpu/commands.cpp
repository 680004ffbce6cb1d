#include "gpu/commands.h"

#include <algorithm>

namespace evflow::gpu {

Commands::Commands(Context& ctx) : ctx_(ctx), cb_(ctx.allocate_command_buffer()), fence_(ctx.create_fence()) {
  if (ctx.options().kernel_times) query_capacity_ = 4096;  // a step's loss terms: a few hundred dispatches
  if (ctx.caps().timestamps) {
    VkQueryPoolCreateInfo qci{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    qci.queryType = VK_QUERY_TYPE_TIMESTAMP;
    qci.queryCount = query_capacity_;
    EVF_VK(vkCreateQueryPool(ctx.device(), &qci, nullptr, &queries_));
  }
  begin();
}

Commands::~Commands() {
  VkDevice d = ctx_.device();
  if (recording_) vkEndCommandBuffer(cb_);
  if (queries_) vkDestroyQueryPool(d, queries_, nullptr);
  for (VkDescriptorPool p : set_pools_) vkDestroyDescriptorPool(d, p, nullptr);
  for (VkBufferView v : views_) vkDestroyBufferView(d, v, nullptr);
  vkDestroyFence(d, fence_, nullptr);
  vkFreeCommandBuffers(d, ctx_.command_pool(), 1, &cb_);
}

void Commands::begin() {
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  EVF_VK(vkBeginCommandBuffer(cb_, &bi));
  recording_ = true;
  empty_ = true;
  marks_.clear();
  for (VkDescriptorPool p : set_pools_) EVF_VK(vkResetDescriptorPool(ctx_.device(), p, 0));
  set_pool_ = 0;
  for (VkBufferView v : views_) vkDestroyBufferView(ctx_.device(), v, nullptr);
  views_.clear();
  if (queries_) {
    vkCmdResetQueryPool(cb_, queries_, 0, query_capacity_);
    vkCmdWriteTimestamp(cb_, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, queries_, 0);
  }
}

Groups Commands::linear_groups(uint64_t n) const {
  Groups g;
  if (n == 0) return {0, 1, 1};
  const uint64_t mx = ctx_.caps().max_workgroup_count[0];
  if (n <= mx) {
    g.x = static_cast<uint32_t>(n);
    return g;
  }
  g.x = static_cast<uint32_t>(mx);
  uint64_t y = (n + mx - 1) / mx;
  if (y > ctx_.caps().max_workgroup_count[1])
    throw Error("dispatch of " + std::to_string(n) + " workgroups exceeds the device grid");
  g.y = static_cast<uint32_t>(y);
  return g;
}

void Commands::barrier() {
  VkMemoryBarrier mb{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
  mb.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_READ_BIT |
                     VK_ACCESS_TRANSFER_WRITE_BIT;
  const VkPipelineStageFlags st = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT;
  vkCmdPipelineBarrier(cb_, st, st, 0, 1, &mb, 0, nullptr, 0, nullptr);
}

static std::string describe(const Kernel::Binding& b) { return std::to_string(b.index) + " (" + b.block + ")"; }

static std::string describe_all(const Kernel& k) {
  std::string s;
  for (const Kernel::Binding& b : k.bindings()) s += (s.empty() ? "" : ", ") + describe(b);
  return s.empty() ? "none" : s;
}

void Commands::dispatch(const std::string& name, std::span<const Bind> bindings, const void* push, uint32_t push_bytes,
                        Groups g) {
  if (g.x == 0 || g.y == 0 || g.z == 0) return;
  const Kernel& k = ctx_.kernel(name);
  const std::vector<Kernel::Binding>& declared = k.bindings();
  std::vector<const Bind*> bound(declared.size(), nullptr);
  for (const Bind& b : bindings) {
    auto host = [&] { return std::to_string(b.slot.index) + " (" + b.slot.block + ")"; };
    auto it = std::lower_bound(declared.begin(), declared.end(), b.slot.index,
                               [](const Kernel::Binding& d, uint32_t i) { return d.index < i; });
    if (it == declared.end() || it->index != b.slot.index)
      throw Error("kernel '" + name + "' has no binding " + host() + "; its SPIR-V declares " + describe_all(k));
    if (!it->block.empty() && it->block != b.slot.block)
      throw Error("kernel '" + name + "': binding " + std::to_string(b.slot.index) + " is block '" + it->block +
                  "' in its SPIR-V, the host binds '" + b.slot.block + "'");
    const size_t i = static_cast<size_t>(it - declared.begin());
    if (bound[i]) throw Error("kernel '" + name + "': binding " + host() + " is bound twice");
    bound[i] = &b;
  }
  for (size_t i = 0; i < declared.size(); ++i)
    if (!bound[i]) throw Error("kernel '" + name + "': binding " + describe(declared[i]) + " is not bound");
  std::vector<VkDescriptorBufferInfo> infos;
  std::vector<VkBufferView> views;
  infos.reserve(bound.size());
  views.reserve(bound.size());
  for (size_t i = 0; i < bound.size(); ++i) {
    const BufferRef& r = bound[i]->buffer;
    if (!r.buffer || !r.buffer->valid()) throw Error("kernel '" + name + "': an unallocated buffer was bound");
    uint64_t range = r.range ? r.range : r.buffer->size() - r.offset;
    const std::string what = "buffer '" + r.buffer->name() + "' in kernel '" + name + "'";
    if (declared[i].texel_format == VK_FORMAT_UNDEFINED) {
      ctx_.check_binding_size(range, what);
      views.push_back(VK_NULL_HANDLE);
    } else {
      views.push_back(texel_view(*r.buffer, r.offset, range, declared[i].texel_format, what));
    }
    infos.push_back({r.buffer->handle(), r.offset, range});
    used(*r.buffer);
  }
  std::vector<VkWriteDescriptorSet> writes(infos.size());
  for (size_t i = 0; i < infos.size(); ++i) {
    writes[i] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    writes[i].dstBinding = declared[i].index;
    writes[i].descriptorCount = 1;
    if (views[i]) {
      writes[i].descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
      writes[i].pTexelBufferView = &views[i];
    } else {
      writes[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
      writes[i].pBufferInfo = &infos[i];
    }
  }
  vkCmdBindPipeline(cb_, VK_PIPELINE_BIND_POINT_COMPUTE, k.pipeline());
  if (!writes.empty()) bind_descriptors(k, writes);
  uint8_t pc[kPushConstantBytes] = {};
  if (push_bytes > kPushConstantBytes) throw Error("push constants above 128 bytes for kernel '" + name + "'");
  if (push_bytes) std::copy_n(static_cast<const uint8_t*>(push), push_bytes, pc);
  vkCmdPushConstants(cb_, k.layout(), VK_SHADER_STAGE_COMPUTE_BIT, 0, kPushConstantBytes, pc);
  vkCmdDispatch(cb_, g.x, g.y, g.z);
  barrier();
  empty_ = false;
  if (ctx_.options().kernel_times) write_timestamp(name, true);
}

// A view of [offset, offset + range) as texels of `format`, kept until the recording's submit has
// run (begin() destroys it). Views are made per dispatch: a buffer that grows gets a new handle.
VkBufferView Commands::texel_view(const Buffer& b, uint64_t offset, uint64_t range, VkFormat format,
                                  const std::string& what) {
  const uint64_t texel = format == VK_FORMAT_R32G32B32A32_SFLOAT ? 16 : 4;
  const DeviceCaps& caps = ctx_.caps();
  range -= range % texel;
  if (range / texel > caps.max_texel_buffer_elements)
    throw Error(what + " needs a texel buffer of " + std::to_string(range / texel) +
                " texels, above this device's maxTexelBufferElements of " +
                std::to_string(caps.max_texel_buffer_elements) + " (" + caps.name + ")");
  if (caps.min_texel_offset_alignment && offset % caps.min_texel_offset_alignment)
    throw Error(what + " is bound at offset " + std::to_string(offset) +
                ", not a multiple of this device's minTexelBufferOffsetAlignment (" +
                std::to_string(caps.min_texel_offset_alignment) + ")");
  VkBufferViewCreateInfo vci{VK_STRUCTURE_TYPE_BUFFER_VIEW_CREATE_INFO};
  vci.buffer = b.handle();
  vci.format = format;
  vci.offset = offset;
  vci.range = range;
  VkBufferView view = VK_NULL_HANDLE;
  EVF_VK(vkCreateBufferView(ctx_.device(), &vci, nullptr, &view));
  views_.push_back(view);
  return view;
}

void Commands::bind_descriptors(const Kernel& k, const std::vector<VkWriteDescriptorSet>& writes) {
  if (!ctx_.bound_descriptor_sets()) {
    ctx_.push_descriptor_set()(cb_, VK_PIPELINE_BIND_POINT_COMPUTE, k.layout(), 0, static_cast<uint32_t>(writes.size()),
                               writes.data());
    return;
  }
  VkDescriptorSet set = allocate_set(k.set_layout());
  std::vector<VkWriteDescriptorSet> w = writes;
  for (VkWriteDescriptorSet& x : w) x.dstSet = set;
  vkUpdateDescriptorSets(ctx_.device(), static_cast<uint32_t>(w.size()), w.data(), 0, nullptr);
  vkCmdBindDescriptorSets(cb_, VK_PIPELINE_BIND_POINT_COMPUTE, k.layout(), 0, 1, &set, 0, nullptr);
}

// A set from the current pool; a full pool moves on to the next one, made when there is none.
VkDescriptorSet Commands::allocate_set(VkDescriptorSetLayout layout) {
  constexpr uint32_t kSetsPerPool = 256, kBindingsPerSet = 32;
  for (;; ++set_pool_) {
    const bool fresh = set_pool_ == set_pools_.size();
    if (fresh) {
      const VkDescriptorPoolSize sizes[] = {{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, kSetsPerPool * kBindingsPerSet},
                                            {VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, kSetsPerPool * kBindingsPerSet}};
      VkDescriptorPoolCreateInfo pci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
      pci.maxSets = kSetsPerPool;
      pci.poolSizeCount = 2;
      pci.pPoolSizes = sizes;
      VkDescriptorPool pool = VK_NULL_HANDLE;
      EVF_VK(vkCreateDescriptorPool(ctx_.device(), &pci, nullptr, &pool));
      set_pools_.push_back(pool);
    }
    VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    ai.descriptorPool = set_pools_[set_pool_];
    ai.descriptorSetCount = 1;
    ai.pSetLayouts = &layout;
    VkDescriptorSet set = VK_NULL_HANDLE;
    const VkResult r = vkAllocateDescriptorSets(ctx_.device(), &ai, &set);
    if (r == VK_SUCCESS) return set;
    if (fresh || (r != VK_ERROR_OUT_OF_POOL_MEMORY && r != VK_ERROR_FRAGMENTED_POOL))
      check(r, "vkAllocateDescriptorSets");
  }
}

void Commands::fill(const Buffer& b, uint32_t value, uint64_t offset, uint64_t bytes) {
  uint64_t n = bytes ? bytes : b.size() - offset;
  n &= ~uint64_t(3);
  if (n == 0) return;
  vkCmdFillBuffer(cb_, b.handle(), offset, n, value);
  used(b);
  barrier();
  empty_ = false;
}

void Commands::copy(const Buffer& src, const Buffer& dst, uint64_t bytes, uint64_t so, uint64_t doff) {
  if (!bytes) return;
  VkBufferCopy r{so, doff, bytes};
  vkCmdCopyBuffer(cb_, src.handle(), dst.handle(), 1, &r);
  used(src);
  used(dst);
  barrier();
  empty_ = false;
}

void Commands::mark(const std::string& name) { write_timestamp(name, false); }

void Commands::write_timestamp(std::string name, bool kernel) {
  if (!queries_) return;
  if (marks_.size() + 1 >= query_capacity_) return;
  marks_.push_back({std::move(name), kernel});
  vkCmdWriteTimestamp(cb_, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, queries_, static_cast<uint32_t>(marks_.size()));
}

// A stage runs from the previous stage mark (or the start) to its own; a kernel from the
// timestamp before its own (the previous dispatch's, a stage mark's or the start).
void Commands::read_timestamps() {
  std::vector<uint64_t> ts(marks_.size() + 1);
  EVF_VK(vkGetQueryPoolResults(ctx_.device(), queries_, 0, static_cast<uint32_t>(ts.size()), ts.size() * 8, ts.data(),
                               8, VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
  const double ms_per_tick = ctx_.caps().timestamp_period_ns * 1e-6;
  std::vector<std::pair<std::string, double>> kernels;
  size_t stage_start = 0;
  for (size_t i = 0; i < marks_.size(); ++i) {
    if (marks_[i].kernel) {
      kernels.emplace_back(marks_[i].name, double(ts[i + 1] - ts[i]) * ms_per_tick);
    } else {
      stage_ms_.emplace_back(marks_[i].name, double(ts[i + 1] - ts[stage_start]) * ms_per_tick);
      stage_start = i + 1;
    }
  }
  if (!kernels.empty()) ctx_.add_kernel_times(kernels);
}

void Commands::used(const Buffer& b) { used_.emplace_back(b.serial(), b.name()); }

// Every buffer the recorded commands use must still hold the allocation they recorded: a buffer
// grown (or freed) after its commands were recorded would have them read and write freed memory.
void Commands::check_used() {
  for (const auto& [serial, name] : used_)
    if (!ctx_.allocation_live(serial)) {
      const std::string what = name;
      used_.clear();
      EVF_VK(vkResetCommandBuffer(cb_, 0));  // from recording back to initial: nothing ends or runs
      begin();
      throw Error("commands were recorded on buffer '" + what +
                  "', which was then grown or freed before they were submitted (a scratch buffer must be sized for "
                  "every use before the first is recorded)");
    }
  used_.clear();
}

void Commands::submit() {
  if (empty_ && marks_.empty()) {  // nothing recorded: no round trip to the device
    stage_ms_.clear();
    return;
  }
  check_used();
  EVF_VK(vkEndCommandBuffer(cb_));
  recording_ = false;
  ctx_.submit_and_wait(cb_, fence_);
  stage_ms_.clear();
  if (queries_ && !marks_.empty()) read_timestamps();
  if (logging_) stage_log_.insert(stage_log_.end(), stage_ms_.begin(), stage_ms_.end());
  EVF_VK(vkResetCommandBuffer(cb_, 0));
  begin();
}

}  // namespace evflow::gpu
