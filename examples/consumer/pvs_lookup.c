/* pvs_lookup LEVEL.pvs X Y Z: the view cell of a viewer at (X, Y, Z) and the objects it
 * may see, as an engine would ask at run time (one line per object: id and name). */
#include <stdio.h>
#include <stdlib.h>

#include <viewcells/runtime.h>

int main(int argc, char** argv) {
  if (argc != 5) {
    fprintf(stderr, "usage: pvs_lookup LEVEL.pvs X Y Z\n");
    return 2;
  }
  char error[512];
  vc_pvs* pvs = NULL;
  if (vc_pvs_open(argv[1], &pvs, error, sizeof error) != 0) {
    fprintf(stderr, "pvs_lookup: %s\n", error);
    return 1;
  }
  const int32_t cell = vc_pvs_locate(pvs, atof(argv[2]), atof(argv[3]), atof(argv[4]));
  if (cell < 0) {
    fprintf(stderr, "pvs_lookup: the point is outside the view space\n");
    vc_pvs_close(pvs);
    return 1;
  }
  const uint32_t* objects = NULL;
  const size_t n = vc_pvs_cell_objects(pvs, cell, &objects);
  printf("cell %d of %u: %zu of %u objects visible\n", cell, vc_pvs_cell_count(pvs), n, vc_pvs_object_count(pvs));
  for (size_t i = 0; i < n; ++i) printf("%u %s\n", objects[i], vc_pvs_object_name(pvs, objects[i]));
  vc_pvs_close(pvs);
  return 0;
}
