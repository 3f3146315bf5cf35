/// Pictures of view cells: a PLY mesh of the cells and a PNG slice, coloured by render cost or
/// merged cell.
#include "viewcells/vis/cell_views.h"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "viewcells/core/binary_file.h"
#include "viewcells/core/error.h"

namespace viewcells {

void cost_colour(double t, unsigned char rgb[3]) {
  t = std::clamp(t, 0.0, 1.0);
  const double r = std::clamp(std::min(4 * t - 1.5, -4 * t + 4.5), 0.0, 1.0);
  const double g = std::clamp(std::min(4 * t - 0.5, -4 * t + 3.5), 0.0, 1.0);
  const double b = std::clamp(std::min(4 * t + 0.5, -4 * t + 2.5), 0.0, 1.0);
  rgb[0] = static_cast<unsigned char>(255 * r);
  rgb[1] = static_cast<unsigned char>(255 * g);
  rgb[2] = static_cast<unsigned char>(255 * b);
}

namespace {

double max_leaf_value(const Subdivision& s, const CellView* view) {
  double m = 0;
  for (int32_t l : s.leaves()) m = std::max(m, view ? view->value[l] : s.nodes[l].pvs_cost);
  return m > 0 ? m : 1.0;
}

void check_view(const Subdivision& s, const CellView* view) {
  if (view && (view->value.size() != s.nodes.size() || view->group.size() != s.nodes.size()))
    throw Error("cell view does not match the subdivision");
}

}  // namespace

CellView merged_cell_view(const Subdivision& s, const MergeHistory& h, const std::vector<int32_t>& cells) {
  const std::vector<int32_t> leaves = s.leaves();
  if (leaves.size() != h.leaf_count) throw Error("the merge history does not match the subdivision");
  CellView view;
  view.value.assign(s.nodes.size(), 0.0);
  view.group.assign(s.nodes.size(), -1);
  for (int32_t c : cells)
    for (uint32_t leaf : h.leaves_under(c)) {
      view.value[leaves[leaf]] = h.nodes[c].pvs_cost;
      view.group[leaves[leaf]] = c;
    }
  return view;
}

void write_cells_ply(const std::string& path, const Subdivision& s, const CellView* view, double shrink) {
  check_view(s, view);
  const std::vector<int32_t> leaves = s.leaves();
  const double max_cost = max_leaf_value(s, view);
  std::string body;
  size_t nv = 0, nf = 0;
  std::string faces;
  for (int32_t l : leaves) {
    const ConvexPolyhedron& cell = s.cells[l];
    if (cell.empty()) throw Error(path, 0, "cell geometry missing (rebuild_cells first)");
    unsigned char rgb[3];
    cost_colour((view ? view->value[l] : s.nodes[l].pvs_cost) / max_cost, rgb);
    const Vec3 c = cell.centroid();
    const size_t base = nv;
    for (const Vec3& p : cell.vertices()) {
      const Vec3 q = c + (p - c) * shrink;
      const float xyz[3] = {static_cast<float>(q.x), static_cast<float>(q.y), static_cast<float>(q.z)};
      body.append(reinterpret_cast<const char*>(xyz), sizeof xyz);
      body.append(reinterpret_cast<const char*>(rgb), 3);
      ++nv;
    }
    for (const PolyFace& f : cell.faces()) {
      const unsigned char count = static_cast<unsigned char>(std::min<size_t>(f.vertices.size(), 255));
      faces.push_back(static_cast<char>(count));
      for (size_t k = 0; k < count; ++k) {
        const int32_t id = static_cast<int32_t>(base + f.vertices[k]);
        faces.append(reinterpret_cast<const char*>(&id), 4);
      }
      ++nf;
    }
  }
  std::string header = "ply\nformat binary_little_endian 1.0\ncomment viewcells: cells coloured by render cost\n";
  header += "element vertex " + std::to_string(nv) +
            "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
            "property uchar blue\nelement face " +
            std::to_string(nf) + "\nproperty list uchar int vertex_indices\nend_header\n";
  write_text_file(path, header + body + faces);
}

void write_rgb_png(const std::string& path, int width, int h, const std::vector<unsigned char>& rgb) {
  check_output_target(path);
  const std::string tmp = temporary_for(path);
  FILE* fp = std::fopen(tmp.c_str(), "wb");
  if (!fp) throw Error(path, 0, "cannot open for writing");
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(fp);
    std::remove(tmp.c_str());
    throw Error(path, 0, "PNG encoding failed");
  }
  png_init_io(png, fp);
  png_set_IHDR(png, info, width, h, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < h; ++y) png_write_row(png, &rgb[3 * static_cast<size_t>(y) * width]);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  if (std::fclose(fp) != 0) {
    std::remove(tmp.c_str());
    throw Error(path, 0, "cannot write PNG");
  }
  install_file(tmp, path);
}

void write_slice_png(const std::string& path, const Subdivision& s, double height, int width, const Scene* scene,
                     const CellView* view) {
  check_view(s, view);
  const Box3& b = s.view_box;
  if (!(height >= b.lo.z && height <= b.hi.z))
    throw Error("slice height " + std::to_string(height) + " is outside the view space (" + std::to_string(b.lo.z) +
                " to " + std::to_string(b.hi.z) + ")");
  if (width < 16 || width > 16384) throw Error("slice width must be between 16 and 16384 pixels");
  const double scale = width / (b.hi.x - b.lo.x);
  const int h = std::max(16, static_cast<int>(std::ceil((b.hi.y - b.lo.y) * scale)));
  const double max_cost = max_leaf_value(s, view);
  std::vector<int32_t> leaf(static_cast<size_t>(width) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < width; ++x)
      leaf[static_cast<size_t>(y) * width + x] =
          s.locate({b.lo.x + (x + 0.5) / scale, b.hi.y - (y + 0.5) / scale, height});
  // Borders are drawn where the cell changes: the leaf, or the group of the view.
  auto cell_of = [&](int32_t l) { return view && l >= 0 ? view->group[l] : l; };
  std::vector<unsigned char> rgb(static_cast<size_t>(width) * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t i = static_cast<size_t>(y) * width + x;
      unsigned char* px = &rgb[3 * i];
      const int32_t l = leaf[i];
      cost_colour(l >= 0 ? (view ? view->value[l] : s.nodes[l].pvs_cost) / max_cost : 0.0, px);
      const int32_t cell = cell_of(l);
      const bool border =
          (x + 1 < width && cell_of(leaf[i + 1]) != cell) || (y + 1 < h && cell_of(leaf[i + width]) != cell);
      if (border)
        for (int c = 0; c < 3; ++c) px[c] = static_cast<unsigned char>(px[c] / 3);
    }
  if (scene) {
    // The scene's cross-section: where triangles cross z = height, drawn in black.
    auto plot = [&](double wx, double wy) {
      const int x = static_cast<int>((wx - b.lo.x) * scale), y = static_cast<int>((b.hi.y - wy) * scale);
      if (x >= 0 && x < width && y >= 0 && y < h) std::memset(&rgb[3 * (static_cast<size_t>(y) * width + x)], 0, 3);
    };
    for (const auto& tri : scene->triangles) {
      Vec3 pts[2];
      int k = 0;
      for (int e = 0; e < 3 && k < 2; ++e) {
        const Vec3 p = scene->vertices[tri[e]], q = scene->vertices[tri[(e + 1) % 3]];
        if ((p.z - height) * (q.z - height) < 0) pts[k++] = p + (q - p) * ((height - p.z) / (q.z - p.z));
      }
      if (k < 2) continue;
      const double len = length(pts[1] - pts[0]) * scale;
      const int steps = std::max(1, static_cast<int>(len * 2));
      for (int i = 0; i <= steps; ++i) {
        const Vec3 p = pts[0] + (pts[1] - pts[0]) * (static_cast<double>(i) / steps);
        plot(p.x, p.y);
      }
    }
  }
  write_rgb_png(path, width, h, rgb);
}

}  // namespace viewcells
