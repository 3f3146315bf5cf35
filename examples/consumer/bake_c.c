/* bake_c [ROOMS]: the C API end to end, in memory. Makes a level of ROOMS x ROOMS rooms (walls
 * with doorways, a crate in each room) as per-object arrays, bakes it with vc_bake (the
 * toolkit, viewcells/bake.h), opens the returned .pvs bytes with the runtime
 * (vc_pvs_open_memory) and asks which cell each room's middle is in and what it sees. No file
 * is read or written: an engine's editor bakes this way. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <viewcells/bake.h>
#include <viewcells/runtime.h>

#define MAX_OBJECTS 2000

static double vertices[MAX_OBJECTS][24];
static char names[MAX_OBJECTS][32];
/* Corner i of a box has x from bit 0, y from bit 1, z from bit 2; each face's two triangles wind
 * counter-clockwise seen from outside (a closed solid: empty-space detection and floors apply). */
static const uint32_t box_faces[36] = {0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
                                       2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5};
static vc_bake_object objects[MAX_OBJECTS];
static size_t count = 0;

/* An axis-aligned box [lo, hi] as the next object. */
static void add_box(const char* name, double x0, double y0, double z0, double x1, double y1, double z1) {
  double* v = vertices[count];
  for (int i = 0; i < 8; ++i) {
    v[3 * i] = i & 1 ? x1 : x0;
    v[3 * i + 1] = i & 2 ? y1 : y0;
    v[3 * i + 2] = i & 4 ? z1 : z0;
  }
  snprintf(names[count], sizeof names[count], "%s", name);
  vc_bake_object o = {names[count], v, 8, box_faces, 12, 0};
  objects[count++] = o;
}

static void print_line(const char* line, void* user) {
  (void)user;
  fprintf(stderr, "%s\n", line);
}

int main(int argc, char** argv) {
  const int rooms = argc > 1 ? atoi(argv[1]) : 3;
  const int verbose = argc > 2 && strcmp(argv[2], "-v") == 0;
  if (rooms < 1 || rooms > 10) {
    fprintf(stderr, "usage: bake_c [ROOMS: 1 to 10] [-v]\n");
    return 2;
  }
  const double size = 10, height = 3, t = 0.2, n = rooms * size;
  char name[32];
  add_box("floor", 0, 0, -t, n, n, 0);
  for (int i = 0; i <= rooms; ++i)
    for (int j = 0; j < rooms; ++j) {
      const double a = j * size, b = a + size, door = i > 0 && i < rooms ? 1.0 : 0.0;
      for (int half = 0; half < 2; ++half) {
        const double lo = half ? (a + b) / 2 + door : a, hi = half ? b : (a + b) / 2 - door;
        snprintf(name, sizeof name, "wall_x%d_%d_%d", i, j, half);
        add_box(name, i * size - t / 2, lo, 0, i * size + t / 2, hi, height);
        snprintf(name, sizeof name, "wall_y%d_%d_%d", i, j, half);
        add_box(name, lo, i * size - t / 2, 0, hi, i * size + t / 2, height);
      }
    }
  for (int i = 0; i < rooms; ++i)
    for (int j = 0; j < rooms; ++j) {
      snprintf(name, sizeof name, "crate%d_%d", i, j);
      add_box(name, i * size + 3, j * size + 3, 0, i * size + 4, j * size + 4, 1);
    }

  char cells[16];
  snprintf(cells, sizeof cells, "%d", rooms * rooms);
  const char* options[] = {"--cells", cells, "--samples", "100000", "--agvs-samples", "200000", NULL};
  vc_bake_result* baked = NULL;
  char error[512];
  if (vc_bake(objects, count, options, NULL, verbose ? print_line : NULL, NULL, &baked, error, sizeof error) != 0) {
    fprintf(stderr, "bake_c: %s\n", error);
    return 1;
  }
  size_t bytes = 0;
  const void* file = vc_bake_result_bytes(baked, &bytes);
  vc_pvs* pvs = NULL;
  if (vc_pvs_open_memory(file, bytes, 0, &pvs, error, sizeof error) != 0) {
    fprintf(stderr, "bake_c: %s\n", error);
    vc_bake_result_free(baked);
    return 1;
  }
  printf("level: %zu objects\n", count);
  printf("cells: %u, %zu bytes as a .pvs\n", vc_pvs_cell_count(pvs), bytes);
  for (int i = 0; i < rooms; ++i) {
    const double at = i * size + 5;
    const int32_t cell = vc_pvs_locate(pvs, at, at, 1.7);
    uint32_t seen = 0;
    for (uint32_t o = 0; o < vc_pvs_object_count(pvs); ++o) seen += vc_pvs_cell_sees(pvs, cell, o) == 1;
    printf("room %d %d: cell %d sees %u objects\n", i, i, cell, seen);
  }
  vc_pvs_close(pvs);
  vc_bake_result_free(baked);
  return 0;
}
