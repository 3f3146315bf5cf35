#pragma once
/// Pictures of view cells for people: the cells as a coloured PLY mesh, and a horizontal
/// slice through them as a PNG, coloured by render cost or by the merged view cells they
/// belong to.
#include <string>
#include <vector>

#include "viewcells/bsp/subdivision.h"
#include "viewcells/merge/merge.h"
#include "viewcells/scene/scene.h"

namespace viewcells {

/// The colour scale of every view: blue -> cyan -> green -> yellow -> red for t in [0, 1].
void cost_colour(double t, unsigned char rgb[3]);

/// How the views below draw the leaves when they show larger cells (e.g. extracted ones):
/// per BSP node, the value its colour comes from and the cell it belongs to.
struct CellView {
  std::vector<double> value;   ///< per node (leaves); colour from blue (low) to red (high)
  std::vector<int32_t> group;  ///< per node (leaves); borders are drawn between groups
};
/// The view of a set of merged cells: every leaf coloured by the r(PVS) of its cell.
CellView merged_cell_view(const Subdivision& s, const MergeHistory& h, const std::vector<int32_t>& cells);

/// Writes the leaves as a binary PLY, every leaf shrunk by `shrink` towards its centre so
/// neighbours stay apart, coloured by render cost r(PVS) from blue (low) to red (high), or by
/// `view` when given.
void write_cells_ply(const std::string& path, const Subdivision& s, const CellView* view = nullptr,
                     double shrink = 0.97);

/// Writes an 8-bit RGB PNG of width x height pixels (rows top first, three bytes a pixel).
/// Written atomically.
void write_rgb_png(const std::string& path, int width, int height, const std::vector<unsigned char>& rgb);

/// Writes a PNG of the horizontal slice z = height through the view space: each cell filled
/// with its render-cost colour, cell borders dark, and (when scene is given) the scene's
/// cross-section in black. `width` pixels along x. `view` as for write_cells_ply.
void write_slice_png(const std::string& path, const Subdivision& s, double height, int width,
                     const Scene* scene = nullptr, const CellView* view = nullptr);

}  // namespace viewcells
