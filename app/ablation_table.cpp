#include "ablation_table.h"

#include <cstdio>
#include <map>

namespace evflow::app {

const std::vector<AblationRow>& ablation_rows() {
  static const std::vector<AblationRow> rows = {
      {"I", "blur-only", {true, false, false, false, false, false, false}},
      {"II", "blur+events", {true, true, false, false, false, false, false}},
      {"III", "blur+events+warp", {true, true, true, false, false, false, false}},
      {"IV", "blur+res", {true, false, false, true, false, false, false}},
      {"V", "blur+events+warp+res", {true, true, true, true, false, false, false}},
      {"VI", "evflow-no-ldi-events", {true, true, true, true, true, false, true}},
      {"VII", "evflow", {true, true, true, true, true, true, true}},
  };
  return rows;
}

std::vector<std::string> ablation_methods() {
  std::vector<std::string> m;
  for (const AblationRow& r : ablation_rows()) m.push_back(r.method);
  return m;
}

namespace {

struct RowScores {
  double psnr = 0, ssim = 0, refined = 0;
  int n = 0;
  std::map<std::string, double> per_scene;  // deblur PSNR
};

std::map<std::string, RowScores> scores_by_method(const nlohmann::json& runs, std::vector<std::string>& scenes) {
  std::map<std::string, RowScores> by;
  for (const auto& r : runs) {
    const std::string scene = r.at("scene").get<std::string>();
    if (std::find(scenes.begin(), scenes.end(), scene) == scenes.end()) scenes.push_back(scene);
    RowScores& s = by[r.at("method").get<std::string>()];
    s.psnr += r.at("deblur_psnr").get<double>();
    s.ssim += r.at("deblur_ssim").get<double>();
    s.refined += r.at("novel_refined_psnr").get<double>();
    s.per_scene[scene] = r.at("deblur_psnr").get<double>();
    ++s.n;
  }
  return by;
}

std::string header(const std::vector<std::string>& scenes) {
  std::string h =
      "| ID | L_blur^gs | L_ev | L_ev^w | L_res | L_blur^ldi | L_ev^ldi | L_joint | method | runs | "
      "deblur PSNR | deblur SSIM | novel refined PSNR |";
  std::string rule = "|---|---|---|---|---|---|---|---|---|---|---|---|---|";
  for (const auto& s : scenes) h += " " + s + " |", rule += "---|";
  return h + "\n" + rule + "\n";
}

}  // namespace

std::string ablation_markdown(const nlohmann::json& runs) {
  std::vector<std::string> scenes;
  const std::map<std::string, RowScores> by = scores_by_method(runs, scenes);
  std::string md = header(scenes);
  for (const AblationRow& row : ablation_rows()) {
    const auto it = by.find(row.method);
    if (it == by.end()) continue;
    const RowScores& s = it->second;
    md += std::string("| ") + row.id + " |";
    for (bool t : row.terms) md += t ? " ✓ |" : "  |";
    char buf[160];
    std::snprintf(buf, sizeof buf, " %s | %d | %.2f | %.4f | %.2f |", row.method, s.n, s.psnr / s.n, s.ssim / s.n,
                  s.refined / s.n);
    md += buf;
    for (const auto& sc : scenes) {
      const auto p = s.per_scene.find(sc);
      if (p == s.per_scene.end()) {
        md += " — |";
        continue;
      }
      std::snprintf(buf, sizeof buf, " %.2f |", p->second);
      md += buf;
    }
    md += "\n";
  }
  return md;
}

}  // namespace evflow::app
