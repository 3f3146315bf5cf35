/* viewcells bake, from C: view cells and their PVSs for a scene held in memory (an engine's or
 * an editor's meshes), with `viewcells bake`'s options and defaults, the result returned in
 * memory as the bytes of a .pvs file (open them with the runtime's vc_pvs_open_memory) and,
 * when asked, also written to a file.
 *
 *   vc_bake_object objects[] = {{"floor", floor_xyz, 4, floor_tris, 2, 0}, ...};
 *   const char* options[] = {"--cells", "64", "--pixel-error", "5", NULL};
 *   vc_bake_result* baked;
 *   char error[512];
 *   if (vc_bake(objects, count, options, NULL, NULL, NULL, &baked, error, sizeof error) != 0)
 *     fprintf(stderr, "%s\n", error);
 *
 * Link viewcells::bake (find_package(viewcells COMPONENTS toolkit)): the whole toolkit, so
 * Embree, TBB, CGAL and the rest come with it. One bake at a time per process; a bake uses
 * every core. */
#ifndef VIEWCELLS_BAKE_H
#define VIEWCELLS_BAKE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* One object of the scene: a triangle mesh of its own. Object ids in the result are the
 * positions in the array given to vc_bake. */
typedef struct vc_bake_object {
  const char* name;          /* NULL: "objectN" */
  const double* vertices;    /* x, y, z per vertex (double, so that large worlds keep their
                                precision; convert float meshes first) */
  uint32_t vertex_count;
  const uint32_t* indices;   /* three vertex indices (into this object's vertices) a triangle */
  uint32_t triangle_count;
  int see_through;           /* non-zero: glass, water, a fence: in PVSs, but hides nothing */
} vc_bake_object;

/* A line of progress, as `viewcells bake` prints it; `user` is vc_bake's. */
typedef void (*vc_bake_log)(const char* line, void* user);

typedef struct vc_bake_result vc_bake_result;

/* Bakes `objects` (object_count of them). `options`: `viewcells bake`'s options as words,
 * NULL-terminated (e.g. {"--cells", "100", NULL}; NULL: none). A budget (--cells or --memory)
 * is required, as on the command line; -o and --report are not options here. `output`: a
 * .pvs file to write as well, replaced only when the bake succeeds (NULL: nothing is
 * written). `log`: called with each progress line (NULL: quiet).
 * Returns 0 and sets *out (free it with vc_bake_result_free); on failure returns non-zero,
 * sets *out to NULL and writes the message into error (NUL-terminated, truncated to
 * error_size; error may be NULL): 1 bad arguments, 2 the bake failed (the message says
 * why: an option, the scene, a limit), 3 out of memory. */
int vc_bake(const vc_bake_object* objects, size_t object_count, const char* const* options, const char* output,
            vc_bake_log log, void* user, vc_bake_result** out, char* error, size_t error_size);

/* The bake's settings as fields, for callers that would rather not write option words:
 * vc_bake_config_default() gives the library's defaults (pipeline::BakeConfig{}, which are
 * `viewcells bake`'s), and vc_bake_with_config bakes with them, parsing nothing. Fields not
 * here keep their defaults; the library decides the rest from the scene and budget (the
 * report's settings.decided says what). */
typedef struct vc_bake_config {
  uint32_t cells;             /* budget: this many view cells ... */
  uint64_t memory_bytes;      /* ... or a .pvs of at most this many bytes (exactly one of the two) */
  int memory_of_lists;        /* non-zero: memory_bytes counts the coded lists alone */
  uint64_t samples;           /* construction samples (default 1,000,000) */
  uint64_t seed;              /* the same seed, the same file, for any number of threads */
  double pixel_error;         /* stop AGVS at this estimated pixel error of 1024x1024 (0: none given) */
  uint64_t agvs_samples;      /* stop AGVS after this many samples (0: none given) */
  double holes;               /* stop once at most this share (0-1) of measuring frames shows a
                                 wrong pixel (0: none) */
  double time_seconds;        /* the whole bake's time limit (0: none) */
  uint32_t near_samples;      /* rays per near-object candidate (0: none; default 2048) */
  int play_space;             /* non-zero (default): cells where players stand, when the scene
                                 has walkable floors */
  int prove_hidden;           /* sort (cell, object) pairs into proven visible, hidden, undecided */
  int conservative;           /* ship the undecided pairs too: no holes by construction */
  double metres_per_unit;     /* 0 (default): the scene's unit taken as metres */
  const double* start_points; /* x, y, z per start point, scene units (NULL: none) */
  size_t start_point_count;
} vc_bake_config;

/* The library's defaults, with no budget: set cells or memory_bytes. */
vc_bake_config vc_bake_config_default(void);

/* As vc_bake, with `config` (non-NULL) instead of option words. */
int vc_bake_with_config(const vc_bake_object* objects, size_t object_count, const vc_bake_config* config,
                        const char* output, vc_bake_log log, void* user, vc_bake_result** out, char* error,
                        size_t error_size);

/* The baked .pvs file's bytes (as written to `output`), owned by the result. */
const void* vc_bake_result_bytes(const vc_bake_result* result, size_t* size);
/* The bake's report as JSON (what `viewcells bake --report` writes), owned by the result. */
const char* vc_bake_result_report(const vc_bake_result* result);
/* View cells baked. */
uint32_t vc_bake_result_cells(const vc_bake_result* result);
void vc_bake_result_free(vc_bake_result* result);

#ifdef __cplusplus
}
#endif

#endif
