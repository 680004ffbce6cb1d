// A flow field as a grid of nodes: n x n tiles over a W x H image, (n + 1)^2 nodes, node (a, b)
// at pixel position (a W / n, b H / n), each holding a displacement (u, v) in pixels; the flow at
// a pixel centre is bilinear in the four nodes of its tile (shaders/flow/flow_math.glsl computes
// the same on the GPU). One tile is an affine-capable field; finer grids follow local motion.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace evflow::flow {

struct FlowGrid {
  uint32_t tiles = 1;
  std::vector<float> nodes;  // (n + 1)^2 * 2: u, v per node, row-major (b * (n + 1) + a)

  explicit FlowGrid(uint32_t n = 1) : tiles(n), nodes(size_t(n + 1) * (n + 1) * 2, 0.0f) {}
  uint32_t side() const { return tiles + 1; }
  size_t node_count() const { return size_t(side()) * side(); }
};

// The cell under pixel-centre coordinate c on an axis of `size` pixels: left node, fraction.
void grid_cell(double c, uint32_t size, uint32_t tiles, uint32_t& a, double& f);
// The flow at every pixel centre, H * W * 2 (u, v interleaved).
std::vector<float> dense_flow(const FlowGrid& g, uint32_t width, uint32_t height);
// The same field on a grid of `tiles` tiles (exact when tiles is a multiple of g.tiles).
FlowGrid refine(const FlowGrid& g, uint32_t tiles, uint32_t width, uint32_t height);
// Total variation of the node grid: mean over neighbouring node pairs of sqrt(|d|^2 + eps^2);
// adds weight * dTV/dnode to grad (same layout as nodes) and returns TV.
double grid_tv(const FlowGrid& g, double weight, std::vector<double>& grad, double eps = 1e-2);

}  // namespace evflow::flow
