#include "train/train_config.h"

#include <functional>
#include <initializer_list>
#include <map>
#include <stdexcept>

namespace evflow {

namespace {

using Setter = std::function<void(TrainConfig&, const std::string&)>;

double to_double(const std::string& k, const std::string& v) {
  try { size_t p; double d = std::stod(v, &p); if (p != v.size()) throw 1; return d; }
  catch (...) { throw std::invalid_argument("config key '" + k + "' expects a number, got '" + v + "'"); }
}
uint64_t to_uint(const std::string& k, const std::string& v) {
  try { size_t p; long long d = std::stoll(v, &p); if (p != v.size() || d < 0) throw 1; return uint64_t(d); }
  catch (...) { throw std::invalid_argument("config key '" + k + "' expects a non-negative integer, got '" + v + "'"); }
}
bool to_bool(const std::string& k, const std::string& v) {
  if (v == "1" || v == "true" || v == "yes") return true;
  if (v == "0" || v == "false" || v == "no") return false;
  throw std::invalid_argument("config key '" + k + "' expects true/false, got '" + v + "'");
}

// The value of `names` whose name is v; the error lists the names.
template <typename E>
E to_enum(const std::string& k, const std::string& v, std::initializer_list<E> values, const char* (*name)(E)) {
  std::string all;
  for (E e : values) {
    if (v == name(e)) return e;
    if (!all.empty()) all += ", ";
    all += name(e);
  }
  throw std::invalid_argument("config key '" + k + "' must be one of " + all + ", got '" + v + "'");
}

const std::map<std::string, Setter>& setters() {
  static const std::map<std::string, Setter> m = {
      {"preset", [](TrainConfig& c, const std::string& v) { c = TrainConfig::preset_named(v); }},
      {"iterations", [](TrainConfig& c, const std::string& v) { c.iterations = uint32_t(to_uint("iterations", v)); }},
      {"init_gaussians", [](TrainConfig& c, const std::string& v) { c.init_gaussians = uint32_t(to_uint("init_gaussians", v)); }},
      {"sh_degree", [](TrainConfig& c, const std::string& v) {
         uint64_t d = to_uint("sh_degree", v);
         if (d > 3) throw std::invalid_argument("config key 'sh_degree' must be 0..3");
         c.sh_degree = int(d); }},
      {"sh_increase_every", [](TrainConfig& c, const std::string& v) { c.sh_increase_every = uint32_t(to_uint("sh_increase_every", v)); }},
      {"lr_means_init", [](TrainConfig& c, const std::string& v) { c.lr_means_init = to_double("lr_means_init", v); }},
      {"lr_means_final", [](TrainConfig& c, const std::string& v) { c.lr_means_final = to_double("lr_means_final", v); }},
      {"lr_sh_dc", [](TrainConfig& c, const std::string& v) { c.lr_sh_dc = to_double("lr_sh_dc", v); }},
      {"lr_sh_rest", [](TrainConfig& c, const std::string& v) { c.lr_sh_rest = to_double("lr_sh_rest", v); }},
      {"lr_opacity", [](TrainConfig& c, const std::string& v) { c.lr_opacity = to_double("lr_opacity", v); }},
      {"lr_log_scales", [](TrainConfig& c, const std::string& v) { c.lr_log_scales = to_double("lr_log_scales", v); }},
      {"lr_quats", [](TrainConfig& c, const std::string& v) { c.lr_quats = to_double("lr_quats", v); }},
      {"ssim_lambda", [](TrainConfig& c, const std::string& v) { c.ssim_lambda = to_double("ssim_lambda", v); }},
      {"loss_space", [](TrainConfig& c, const std::string& v) {
         c.loss_space = to_enum("loss_space", v, {LossSpace::Linear, LossSpace::Srgb}, loss_space_name); }},
      {"mode", [](TrainConfig& c, const std::string& v) {
         c.mode = to_enum("mode", v, {TrainMode::Plain, TrainMode::Blur}, mode_name); }},
      {"virtual_frames", [](TrainConfig& c, const std::string& v) { c.virtual_frames = uint32_t(to_uint("virtual_frames", v)); }},
      {"lr_trajectory_init", [](TrainConfig& c, const std::string& v) { c.lr_trajectory_init = to_double("lr_trajectory_init", v); }},
      {"lr_trajectory_final", [](TrainConfig& c, const std::string& v) { c.lr_trajectory_final = to_double("lr_trajectory_final", v); }},
      {"target", [](TrainConfig& c, const std::string& v) {
         c.target = to_enum("target", v, {TrainTarget::Blurry, TrainTarget::Sharp, TrainTarget::Edi}, target_name); }},
      {"method", [](TrainConfig& c, const std::string& v) { c.apply_method(v); }},
      {"event_weight", [](TrainConfig& c, const std::string& v) { c.event_weight = to_double("event_weight", v); }},
      {"event_theta_pos", [](TrainConfig& c, const std::string& v) { c.event_theta_pos = to_double("event_theta_pos", v); }},
      {"event_theta_neg", [](TrainConfig& c, const std::string& v) { c.event_theta_neg = to_double("event_theta_neg", v); }},
      {"event_norm_floor", [](TrainConfig& c, const std::string& v) { c.event_norm_floor = to_double("event_norm_floor", v); }},
      {"event_from", [](TrainConfig& c, const std::string& v) { c.event_from = to_double("event_from", v); }},
      {"event_flip_until", [](TrainConfig& c, const std::string& v) { c.event_flip_until = to_double("event_flip_until", v); }},
      {"event_flip_margin", [](TrainConfig& c, const std::string& v) { c.event_flip_margin = to_double("event_flip_margin", v); }},
      {"pose_refine", [](TrainConfig& c, const std::string& v) { c.pose_refine = to_bool("pose_refine", v); }},
      {"lr_pose_init", [](TrainConfig& c, const std::string& v) { c.lr_pose_init = to_double("lr_pose_init", v); }},
      {"lr_pose_final", [](TrainConfig& c, const std::string& v) { c.lr_pose_final = to_double("lr_pose_final", v); }},
      {"antialiased", [](TrainConfig& c, const std::string& v) { c.antialiased = to_bool("antialiased", v); }},
      {"background", [](TrainConfig& c, const std::string& v) {
         float r, g, b;
         if (std::sscanf(v.c_str(), "%f,%f,%f", &r, &g, &b) != 3)
           throw std::invalid_argument("config key 'background' expects r,g,b, got '" + v + "'");
         c.background = {r, g, b}; }},
      {"seed", [](TrainConfig& c, const std::string& v) { c.seed = to_uint("seed", v); }},
      {"log_every", [](TrainConfig& c, const std::string& v) { c.log_every = uint32_t(std::max<uint64_t>(1, to_uint("log_every", v))); }},
      {"densify", [](TrainConfig& c, const std::string& v) { c.densify = to_bool("densify", v); }},
      {"densify_from", [](TrainConfig& c, const std::string& v) { c.densify_from = uint32_t(to_uint("densify_from", v)); }},
      {"densify_until", [](TrainConfig& c, const std::string& v) { c.densify_until = uint32_t(to_uint("densify_until", v)); }},
      {"densify_every", [](TrainConfig& c, const std::string& v) { c.densify_every = uint32_t(to_uint("densify_every", v)); }},
      {"densify_grad_threshold", [](TrainConfig& c, const std::string& v) { c.densify_grad_threshold = to_double("densify_grad_threshold", v); }},
      {"prune_screen_px", [](TrainConfig& c, const std::string& v) { c.prune_screen_px = to_double("prune_screen_px", v); }},
      {"prune_world_scale", [](TrainConfig& c, const std::string& v) { c.prune_world_scale = to_double("prune_world_scale", v); }},
      {"opacity_reset_every", [](TrainConfig& c, const std::string& v) { c.opacity_reset_every = uint32_t(to_uint("opacity_reset_every", v)); }},
      {"max_gaussians", [](TrainConfig& c, const std::string& v) { c.max_gaussians = uint32_t(to_uint("max_gaussians", v)); }},
      {"checkpoint_every", [](TrainConfig& c, const std::string& v) { c.checkpoint_every = uint32_t(to_uint("checkpoint_every", v)); }},
  };
  return m;
}

}  // namespace

const char* loss_space_name(LossSpace s) { return s == LossSpace::Linear ? "linear" : "srgb"; }
const char* mode_name(TrainMode m) { return m == TrainMode::Plain ? "plain" : "blur"; }
const char* target_name(TrainTarget t) {
  switch (t) {
    case TrainTarget::Blurry: return "blurry";
    case TrainTarget::Sharp: return "sharp";
    case TrainTarget::Edi: return "edi";
  }
  return "?";
}

TrainConfig TrainConfig::preset_named(const std::string& name) {
  TrainConfig c;
  if (name == "fast") {
    c.preset = "fast";
  } else if (name == "paper") {
    c.preset = "paper";
    c.iterations = 40000;
    c.init_gaussians = 100000;
    c.sh_increase_every = 1000;
    c.max_gaussians = 0;
    c.checkpoint_every = 5000;
    c.lr_trajectory_init = 1e-3;
    c.lr_trajectory_final = 1e-5;
  } else {
    throw std::invalid_argument("unknown preset '" + name + "' (fast, paper)");
  }
  return c;
}

void TrainConfig::apply_method(const std::string& name) {
  if (name == "plain") { mode = TrainMode::Plain; target = TrainTarget::Blurry; event_weight = 0; }
  else if (name == "edi") { mode = TrainMode::Plain; target = TrainTarget::Edi; event_weight = 0; }
  else if (name == "blur-only") { mode = TrainMode::Blur; target = TrainTarget::Blurry; event_weight = 0; }
  else if (name == "blur+events") { mode = TrainMode::Blur; target = TrainTarget::Blurry; event_weight = 0.1; }
  else throw std::invalid_argument("unknown method '" + name + "' (plain, edi, blur-only, blur+events)");
}

void TrainConfig::set(const std::string& key, const std::string& value) {
  auto it = setters().find(key);
  if (it == setters().end()) throw std::invalid_argument("unknown config key '" + key + "'");
  it->second(*this, value);
}

void TrainConfig::apply_json(const nlohmann::json& j) {
  if (!j.is_object()) throw std::invalid_argument("config must be a JSON object");
  // A preset, then a method, then every other key (so explicit keys win).
  if (j.contains("preset")) set("preset", j["preset"].get<std::string>());
  if (j.contains("method")) set("method", j["method"].get<std::string>());
  for (auto& [k, v] : j.items()) {
    if (k == "preset" || k == "method") continue;
    std::string s;
    if (v.is_string()) s = v.get<std::string>();
    else if (v.is_boolean()) s = v.get<bool>() ? "true" : "false";
    else if (v.is_array() && v.size() == 3) s = std::to_string(v[0].get<double>()) + "," + std::to_string(v[1].get<double>()) + "," + std::to_string(v[2].get<double>());
    else if (v.is_number_integer() || v.is_number_unsigned()) s = std::to_string(v.get<long long>());
    else s = v.dump();
    set(k, s);
  }
}

nlohmann::json TrainConfig::to_json() const {
  return {{"preset", preset}, {"iterations", iterations}, {"init_gaussians", init_gaussians}, {"sh_degree", sh_degree},
          {"sh_increase_every", sh_increase_every}, {"lr_means_init", lr_means_init}, {"lr_means_final", lr_means_final},
          {"lr_sh_dc", lr_sh_dc}, {"lr_sh_rest", lr_sh_rest}, {"lr_opacity", lr_opacity}, {"lr_log_scales", lr_log_scales},
          {"lr_quats", lr_quats}, {"ssim_lambda", ssim_lambda}, {"loss_space", loss_space_name(loss_space)}, {"mode", mode_name(mode)}, {"virtual_frames", virtual_frames},
          {"lr_trajectory_init", lr_trajectory_init}, {"lr_trajectory_final", lr_trajectory_final}, {"target", target_name(target)}, {"antialiased", antialiased},
          {"event_weight", event_weight}, {"event_theta_pos", event_theta_pos}, {"event_theta_neg", event_theta_neg},
          {"event_norm_floor", event_norm_floor}, {"event_from", event_from}, {"event_flip_until", event_flip_until}, {"event_flip_margin", event_flip_margin}, {"pose_refine", pose_refine}, {"lr_pose_init", lr_pose_init},
          {"lr_pose_final", lr_pose_final},
          {"background", {background[0], background[1], background[2]}}, {"seed", seed}, {"log_every", log_every},
          {"checkpoint_every", checkpoint_every}, {"densify", densify}, {"densify_from", densify_from},
          {"densify_until", densify_until}, {"densify_every", densify_every}, {"densify_grad_threshold", densify_grad_threshold},
          {"prune_screen_px", prune_screen_px}, {"prune_world_scale", prune_world_scale},
          {"opacity_reset_every", opacity_reset_every}, {"max_gaussians", max_gaussians}};
}

std::vector<std::string> TrainConfig::keys() {
  std::vector<std::string> k;
  for (auto& [name, s] : setters()) k.push_back(name);
  return k;
}

}  // namespace evflow
