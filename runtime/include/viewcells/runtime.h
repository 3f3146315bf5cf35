/* viewcells runtime: read a .pvs file in a game engine or any other consumer.
 *
 * A small C API over one file written by `viewcells bake`, `viewcells compress` or
 * `viewcells pvs`: locate the view cell of a point, then read that cell's potentially
 * visible objects as a sorted list or as a bit row. It depends on zstd only (no Embree,
 * CGAL, TBB or Boost), and the file is validated as strictly as the toolkit reads it: a
 * corrupt, truncated or foreign file gives an error message, never a crash.
 *
 * Point location is the toolkit's own: the same BSP, the same side of every plane (axis
 * planes compare one coordinate; other planes use an exact orientation predicate), so a
 * point gets the cell that `viewcells query` names for it.
 *
 * Lookups are O(1) after location: opening decodes every cell's visible set once into one
 * array (4 bytes per entry; see vc_pvs_memory_bytes). A handle is read-only after opening
 * and may be shared between threads.
 *
 * Every function is defined for every argument: a NULL handle gives 0, "", -1 or NaN (for
 * vc_pvs_view_box) and never dereferences it, NULL output pointers are skipped, a point
 * location takes any doubles (NaN, infinities, denormals) and any view box a valid file can
 * carry. */
#ifndef VIEWCELLS_RUNTIME_H
#define VIEWCELLS_RUNTIME_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct vc_pvs vc_pvs;

/* Opens and validates a .pvs file. On success returns 0 and sets *out (close it with
 * vc_pvs_close). On failure returns a non-zero code, sets *out to NULL and writes a message
 * naming the file into error (NUL-terminated, truncated to error_size; error may be NULL). */
int vc_pvs_open(const char* path, vc_pvs** out, char* error, size_t error_size);
/* As vc_pvs_open, validated as strictly, but the handle keeps the hierarchy's lists coded (the
 * file's format 2 coding, plus 8 bytes per hierarchy node) instead of every cell's expanded
 * visible set: a fraction of the memory, and each cell's set is decoded along its path to the
 * root when asked for (vc_pvs_cell_objects_copy, _bits, _sees). A compact handle has no lists
 * to point at: vc_pvs_cell_objects and vc_pvs_locate_objects give NULL and 0 for it. */
int vc_pvs_open_compact(const char* path, vc_pvs** out, char* error, size_t error_size);
/* As vc_pvs_open (compact 0) or vc_pvs_open_compact (compact 1), from the `size` bytes of a
 * .pvs file in memory (e.g. what vc_bake returns): validated as strictly; the handle keeps no
 * pointer into them. Messages name the file "(memory)". */
int vc_pvs_open_memory(const void* bytes, size_t size, int compact, vc_pvs** out, char* error, size_t error_size);
void vc_pvs_close(vc_pvs* pvs);
/* 1 for a handle from vc_pvs_open_compact, else 0. */
int vc_pvs_is_compact(const vc_pvs* pvs);

uint32_t vc_pvs_cell_count(const vc_pvs* pvs);
uint32_t vc_pvs_object_count(const vc_pvs* pvs);
/* Bytes of one bit row: (object_count + 7) / 8. */
size_t vc_pvs_row_bytes(const vc_pvs* pvs);
/* The view box: lo[3] and hi[3]. Points outside it are in no cell. */
void vc_pvs_view_box(const vc_pvs* pvs, double lo[3], double hi[3]);
/* The fingerprint of the scene the PVSs were computed for (as `viewcells info` hashes it). */
uint64_t vc_pvs_scene_fingerprint(const vc_pvs* pvs);
/* How the view cells were chosen (e.g. "5000 cells (count)"); owned by the handle. */
const char* vc_pvs_rule(const vc_pvs* pvs);
/* The object's name in the scene, or "" when the file holds no names or the id is out of
 * range; owned by the handle. */
const char* vc_pvs_object_name(const vc_pvs* pvs, uint32_t object);
/* Bytes the handle holds in memory. */
size_t vc_pvs_memory_bytes(const vc_pvs* pvs);
/* Of those, the bytes of the visible sets: a compact handle's coded lists, bit offsets and
 * parents; an expanded handle's ids and per-cell offsets. */
size_t vc_pvs_list_bytes(const vc_pvs* pvs);

/* The view cell containing (x, y, z), or -1 outside the view space (or for a non-finite
 * point). */
int32_t vc_pvs_locate(const vc_pvs* pvs, double x, double y, double z);
/* Both at once, the per-frame call: returns the cell containing (x, y, z) (or -1) and sets
 * *objects and *count to its visible objects (NULL and 0 outside). */
int32_t vc_pvs_locate_objects(const vc_pvs* pvs, double x, double y, double z, const uint32_t** objects,
                              size_t* count);
/* The visible objects of `cell`: sets *objects to its sorted ids (owned by the handle) and
 * returns their count; 0 and NULL for a cell out of range. */
size_t vc_pvs_cell_objects(const vc_pvs* pvs, int32_t cell, const uint32_t** objects);
/* Copies the cell's sorted visible objects into objects (at most capacity of them; objects may
 * be NULL with capacity 0) and returns how many it has: compact handles or not, and safe to call
 * from several threads at once. 0 for a cell out of range. */
size_t vc_pvs_cell_objects_copy(const vc_pvs* pvs, int32_t cell, uint32_t* objects, size_t capacity);
/* Writes the cell's bit row (bit o of byte o / 8 set for each visible object o) into row,
 * which holds row_bytes bytes. Returns 0, or -1 when the cell is out of range or row_bytes
 * is less than vc_pvs_row_bytes (row is then left as it was). */
int vc_pvs_cell_bits(const vc_pvs* pvs, int32_t cell, uint8_t* row, size_t row_bytes);
/* 1 when `object` is in the cell's visible set, else 0 (binary search). */
int vc_pvs_cell_sees(const vc_pvs* pvs, int32_t cell, uint32_t object);

#ifdef __cplusplus
}
#endif

#endif /* VIEWCELLS_RUNTIME_H */
