// The paper's ablation (its Table 3) as `evflow experiment --ablation` runs it: seven rows, each
// a training method, and their table (DIR/ablation.md): which terms each row uses, its scores
// averaged over the scenes and seeds, and each scene's deblur PSNR.
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace evflow::app {

struct AblationRow {
  const char* id;      // I .. VII
  const char* method;  // the `method` it trains with
  // The terms it uses, in the table's column order: L_blur^gs, L_ev, L_ev^w, L_res,
  // L_blur^ldi, L_ev^ldi, L_joint.
  std::vector<bool> terms;
};

const std::vector<AblationRow>& ablation_rows();
std::vector<std::string> ablation_methods();

// The markdown table from experiment.json's runs (objects with scene, method, deblur_psnr,
// deblur_ssim, novel_refined_psnr); rows without runs are left out, a row with fewer runs than
// the others says so.
std::string ablation_markdown(const nlohmann::json& runs);

}  // namespace evflow::app
