// Commands: records dispatches into one command buffer, inserts a full compute/transfer memory
// barrier after each command (so stages never race), writes named timestamps, and submits.
#pragma once
#include <initializer_list>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "common/shared_prelude.h"
#include "gpu/buffer.h"
#include "gpu/kernel.h"

namespace evflow::gpu {

// A buffer for one binding of a kernel, named by the EVF_BIND constant of the kernel's layout
// header (shaders/<module>/<module>_layout.h): {shaderio::kAdamBindParam, params}.
struct Bind {
  shaderio::BindSlot slot;
  BufferRef buffer;
};

struct Groups {
  uint32_t x = 1, y = 1, z = 1;
};

class Commands {
 public:
  explicit Commands(Context& ctx);
  ~Commands();
  Commands(const Commands&) = delete;
  Commands& operator=(const Commands&) = delete;

  Context& context() const { return ctx_; }

  // Workgroup grid for `n_groups` linear groups: x up to the device limit, then y. Shaders
  // recover the linear index with evf_linear_group() (shaders/common/dispatch.glsl).
  Groups linear_groups(uint64_t n_groups) const;
  static uint32_t div_up(uint64_t n, uint32_t d) { return static_cast<uint32_t>((n + d - 1) / d); }

  // Binds each buffer at its slot's index and runs the kernel. Throws unless the slots are
  // exactly the bindings the kernel's SPIR-V declares, each once, with the same block names.
  void dispatch(const std::string& kernel, std::span<const Bind> bindings, const void* push, uint32_t push_bytes,
                Groups groups);
  template <class PC>
  void dispatch(const std::string& kernel, std::initializer_list<Bind> bindings, const PC& pc, Groups groups) {
    static_assert(sizeof(PC) <= kPushConstantBytes, "push constants above 128 bytes");
    dispatch(kernel, std::span<const Bind>(bindings.begin(), bindings.size()), &pc, sizeof(PC), groups);
  }
  // The same with a binding list built at run time (bindings only some builds declare).
  template <class PC>
  void dispatch(const std::string& kernel, const std::vector<Bind>& bindings, const PC& pc, Groups groups) {
    static_assert(sizeof(PC) <= kPushConstantBytes, "push constants above 128 bytes");
    dispatch(kernel, std::span<const Bind>(bindings), &pc, sizeof(PC), groups);
  }
  void fill(const Buffer& b, uint32_t value, uint64_t offset = 0, uint64_t bytes = 0);
  void copy(const Buffer& src, const Buffer& dst, uint64_t bytes, uint64_t src_offset = 0, uint64_t dst_offset = 0);

  // Ends the stage `name`: its time is from the previous mark (or the start) to here.
  void mark(const std::string& name);

  // Submits, waits, and makes the buffer ready for recording again. With nothing recorded (no
  // command, no mark) it returns at once: no submit, no stage times.
  void submit();

  // Stage times (ms) of the last submit, in recording order.
  const std::vector<std::pair<std::string, double>>& stage_ms() const { return stage_ms_; }

  // For work that submits several times (a step's loss terms): from start_stage_log() on, every
  // submit's stage times are kept, in order, until take_stage_log() returns them and stops.
  void start_stage_log() { stage_log_.clear(), logging_ = true; }
  std::vector<std::pair<std::string, double>> take_stage_log() {
    logging_ = false;
    return std::move(stage_log_);
  }

 private:
  void begin();
  void barrier();
  // Binds the descriptor writes of one dispatch: pushed, or (GPU-assisted validation) in a set
  // allocated from this recording's pools, which begin() resets.
  void bind_descriptors(const Kernel& k, const std::vector<VkWriteDescriptorSet>& writes);
  VkDescriptorSet allocate_set(VkDescriptorSetLayout layout);
  VkBufferView texel_view(const Buffer& b, uint64_t offset, uint64_t range, VkFormat format, const std::string& what);
  std::vector<VkBufferView> views_;  // the texel views of this recording
  std::vector<VkDescriptorPool> set_pools_;
  size_t set_pool_ = 0;  // the pool allocate_set takes from
  Context& ctx_;
  VkCommandBuffer cb_ = VK_NULL_HANDLE;
  VkFence fence_ = VK_NULL_HANDLE;
  VkQueryPool queries_ = VK_NULL_HANDLE;
  uint32_t query_capacity_ = 256;
  // Timestamps in recording order after the start's: stage marks, and (ContextOptions::
  // kernel_times) one after each dispatch, named by its kernel.
  struct Mark {
    std::string name;
    bool kernel = false;
  };
  std::vector<Mark> marks_;
  void write_timestamp(std::string name, bool kernel);
  void read_timestamps();
  std::vector<std::pair<std::string, double>> stage_ms_;
  std::vector<std::pair<std::string, double>> stage_log_;
  bool logging_ = false;
  std::vector<std::pair<uint64_t, std::string>> used_;  // the allocations the recorded commands use, by name
  void used(const Buffer& b);
  void check_used();
  bool recording_ = false;
  bool empty_ = true;
};

}  // namespace evflow::gpu
