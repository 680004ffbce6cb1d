// TrainConfig's settings tables: the JSON they write, parsing and its errors, and the key tables
// in docs/training.md.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>

#include "cli_helpers.h"
#include "train/train_config.h"

using namespace evflow;

namespace {

// to_json() as run folders hold it (RunFolder reads them back with apply_json).
const char* kDefaultJson =
    R"({"antialiased":false,"background":[0.0,0.0,0.0],"blur_upsample":1,"checkpoint_every":1000,"densify":true,"densify_every":100,"densify_from":500,"densify_grad_threshold":0.0002,"densify_until":15000,"edi_keep_mid":false,"edi_mid_lr":0.0,"edi_warmup":0.0,"edi_warmup_motion":0.0,"event_flip_margin":0.05,"event_flip_until":0.8,"event_from":0.3,"event_norm_floor":0.001,"event_pool":1,"event_theta_neg":0.0,"event_theta_pos":0.0,"event_weight":0.0,"event_weight_end":0.0,"flow":"events","flow_model_from":0.0,"flow_refresh":100,"init":"random","init_gaussians":20000,"iterations":1500,"joint_from":0.0,"joint_ldi_share":1.0,"joint_weight":1.0,"ldi":false,"ldi_anchor_weight":1.0,"ldi_blur_weight":1.0,"ldi_crop":48,"ldi_event_weight":0.1,"ldi_init_lr":0.003,"ldi_init_steps":300,"ldi_lr":0.001,"ldi_widths":"32,16,16,1","log_every":100,"loss_space":"srgb","lr_log_scales":0.005,"lr_means_final":1.6e-06,"lr_means_init":0.00016,"lr_opacity":0.05,"lr_pose_final":1e-05,"lr_pose_init":0.001,"lr_quats":0.001,"lr_sh_dc":0.0025,"lr_sh_rest":0.000125,"lr_trajectory_final":0.0006,"lr_trajectory_init":0.006,"max_gaussians":30000,"mode":"plain","opacity_reset_every":3000,"pose_refine":false,"preset":"fast","prune_screen_px":0.0,"prune_world_scale":0.0,"res_prior":"assets/residual_prior.safetensors","res_weight":0.0,"seed":0,"sh_degree":3,"sh_increase_every":500,"splats_from":0.0,"ssim_lambda":0.2,"target":"blurry","trajectory_init_sigma":1e-05,"upsample_from":0.0,"virtual_frames":3,"warp_weight":0.0})";
const char* kPaperJson =
    R"({"antialiased":false,"background":[0.0,0.0,0.0],"blur_upsample":1,"checkpoint_every":5000,"densify":true,"densify_every":100,"densify_from":500,"densify_grad_threshold":0.0002,"densify_until":15000,"edi_keep_mid":false,"edi_mid_lr":0.0,"edi_warmup":0.0,"edi_warmup_motion":0.0,"event_flip_margin":0.05,"event_flip_until":0.8,"event_from":0.3,"event_norm_floor":0.001,"event_pool":1,"event_theta_neg":0.0,"event_theta_pos":0.0,"event_weight":0.0,"event_weight_end":0.0,"flow":"events","flow_model_from":0.0,"flow_refresh":100,"init":"random","init_gaussians":100000,"iterations":40000,"joint_from":0.0,"joint_ldi_share":1.0,"joint_weight":1.0,"ldi":false,"ldi_anchor_weight":1.0,"ldi_blur_weight":1.0,"ldi_crop":0,"ldi_event_weight":0.1,"ldi_init_lr":0.003,"ldi_init_steps":300,"ldi_lr":0.001,"ldi_widths":"32,64,128,64,16,1","log_every":100,"loss_space":"srgb","lr_log_scales":0.005,"lr_means_final":1.6e-06,"lr_means_init":0.00016,"lr_opacity":0.05,"lr_pose_final":1e-05,"lr_pose_init":0.001,"lr_quats":0.001,"lr_sh_dc":0.0025,"lr_sh_rest":0.000125,"lr_trajectory_final":1e-05,"lr_trajectory_init":0.001,"max_gaussians":0,"mode":"plain","opacity_reset_every":3000,"pose_refine":false,"preset":"paper","prune_screen_px":0.0,"prune_world_scale":0.0,"res_prior":"assets/residual_prior.safetensors","res_weight":0.0,"seed":0,"sh_degree":3,"sh_increase_every":1000,"splats_from":0.0,"ssim_lambda":0.2,"target":"blurry","trajectory_init_sigma":1e-05,"upsample_from":0.0,"virtual_frames":3,"warp_weight":0.0})";
// method=blur+events background=0.1,0.2,0.3 seed=7 loss_space=linear target=edi pose_refine=yes log_every=0
const char* kMixedJson =
    R"({"antialiased":false,"background":[0.10000000149011612,0.20000000298023224,0.30000001192092896],"blur_upsample":1,"checkpoint_every":1000,"densify":true,"densify_every":100,"densify_from":500,"densify_grad_threshold":0.0002,"densify_until":15000,"edi_keep_mid":false,"edi_mid_lr":0.0,"edi_warmup":0.0,"edi_warmup_motion":0.0,"event_flip_margin":0.05,"event_flip_until":0.8,"event_from":0.3,"event_norm_floor":0.001,"event_pool":1,"event_theta_neg":0.0,"event_theta_pos":0.0,"event_weight":0.1,"event_weight_end":0.0,"flow":"events","flow_model_from":0.0,"flow_refresh":100,"init":"random","init_gaussians":20000,"iterations":1500,"joint_from":0.0,"joint_ldi_share":1.0,"joint_weight":1.0,"ldi":false,"ldi_anchor_weight":1.0,"ldi_blur_weight":1.0,"ldi_crop":48,"ldi_event_weight":0.1,"ldi_init_lr":0.003,"ldi_init_steps":300,"ldi_lr":0.001,"ldi_widths":"32,16,16,1","log_every":1,"loss_space":"linear","lr_log_scales":0.005,"lr_means_final":1.6e-06,"lr_means_init":0.00016,"lr_opacity":0.05,"lr_pose_final":1e-05,"lr_pose_init":0.001,"lr_quats":0.001,"lr_sh_dc":0.0025,"lr_sh_rest":0.000125,"lr_trajectory_final":0.0006,"lr_trajectory_init":0.006,"max_gaussians":30000,"mode":"blur","opacity_reset_every":3000,"pose_refine":true,"preset":"fast","prune_screen_px":0.0,"prune_world_scale":0.0,"res_prior":"assets/residual_prior.safetensors","res_weight":0.0,"seed":7,"sh_degree":3,"sh_increase_every":500,"splats_from":0.0,"ssim_lambda":0.2,"target":"edi","trajectory_init_sigma":1e-05,"upsample_from":0.0,"virtual_frames":3,"warp_weight":0.0})";

TrainConfig mixed() {
  TrainConfig c;
  for (const char* kv : {"method=blur+events", "background=0.1,0.2,0.3", "seed=7", "loss_space=linear", "target=edi",
                         "pose_refine=yes", "log_every=0"}) {
    const std::string s = kv;
    c.set(s.substr(0, s.find('=')), s.substr(s.find('=') + 1));
  }
  return c;
}

}  // namespace

TEST_CASE("train config: to_json writes the keys and values run folders hold", "[train][config]") {
  CHECK(TrainConfig{}.to_json().dump() == kDefaultJson);
  CHECK(TrainConfig::preset_named("paper").to_json().dump() == kPaperJson);
  CHECK(mixed().to_json().dump() == kMixedJson);
  // Every key but "method" (which only sets others) is written.
  const nlohmann::json j = TrainConfig{}.to_json();
  std::vector<std::string> written;
  for (auto& [k, v] : j.items()) written.push_back(k);
  std::vector<std::string> keys = TrainConfig::keys();
  keys.erase(std::find(keys.begin(), keys.end(), "method"));
  std::sort(keys.begin(), keys.end());
  CHECK(written == keys);
}

TEST_CASE("train config: to_json, apply_json, to_json round-trips", "[train][config]") {
  const std::vector<TrainConfig> configs = {TrainConfig{}, TrainConfig::preset_named("paper"), mixed()};
  for (const TrainConfig& c : configs) {
    TrainConfig d;
    d.apply_json(c.to_json());
    CHECK(d.to_json().dump() == c.to_json().dump());
  }
}

TEST_CASE("train config: apply_json applies preset, then method, then the other keys", "[train][config]") {
  TrainConfig c;
  c.apply_json(
      nlohmann::json::parse(R"({"event_weight": 0.5, "iterations": 7, "method": "blur+events", "preset": "paper"})"));
  CHECK(c.preset == "paper");
  CHECK(c.mode == TrainMode::Blur);
  CHECK(c.event_weight == 0.5);
  CHECK(c.iterations == 7);
  CHECK(c.init_gaussians == 100000);
  REQUIRE_THROWS_WITH(c.apply_json(nlohmann::json::array()), Catch::Contains("JSON object"));
}

TEST_CASE("train config: bad values are refused naming the key and what it expects", "[train][config]") {
  TrainConfig c;
  const std::vector<std::array<std::string, 3>> cases = {
      {"iterations", "-1", "config key 'iterations' expects a non-negative integer, got '-1'"},
      {"lr_quats", "fast", "config key 'lr_quats' expects a finite number, got 'fast'"},
      {"event_weight", "nan", "config key 'event_weight' expects a finite number, got 'nan'"},
      {"lr_means_init", "inf", "config key 'lr_means_init' expects a finite number, got 'inf'"},
      {"trajectory_init_sigma", "0.5", "config key 'trajectory_init_sigma' must be 0..0.1, got '0.5'"},
      {"densify", "maybe", "config key 'densify' expects true/false, got 'maybe'"},
      {"background", "1,2", "config key 'background' expects r,g,b, got '1,2'"},
      {"sh_degree", "4", "config key 'sh_degree' must be 0..3"},
      {"loss_space", "log", "config key 'loss_space' must be one of linear, srgb, got 'log'"},
      {"mode", "sharp", "config key 'mode' must be one of plain, blur, got 'sharp'"},
      {"target", "x", "config key 'target' must be one of blurry, sharp, edi, got 'x'"},
      {"preset", "slow", "unknown preset 'slow' (fast, paper)"},
      {"method", "nerf",
       "unknown method 'nerf' (plain, edi, blur-only, blur+events, blur+events+warp, blur+events+flow, blur+res, "
       "blur+events+warp+res, evflow-no-ldi-events, evflow)"},
      {"iterationz", "1", "unknown config key 'iterationz'"},
  };
  for (auto& [key, value, message] : cases) {
    INFO(key << "=" << value);
    REQUIRE_THROWS_WITH(c.set(key, value), Catch::Contains(message));
  }
  c.set("log_every", "0");
  CHECK(c.log_every == 1);
  c.set("sh_degree", "0");
  CHECK(c.sh_degree == 0);
}

TEST_CASE("train config: docs/training.md lists every key with its default and meaning", "[train][config][docs]") {
  INFO("regenerate the tables in docs/training.md with build/evflow train --keys");
  CHECK(test::generated_section("training.md", "evflow train --keys") == TrainConfig::describe_markdown());
}
