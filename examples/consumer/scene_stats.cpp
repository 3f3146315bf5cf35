// scene_stats SCENE: loads a scene with the whole library (COMPONENTS toolkit) and prints
// its objects and triangles, as a tool built on viewcells would start. As a front end, it
// brings the formats it wants beyond the library's own: here Quake 3 maps.
#include <iostream>

#include <viewcells/core/error.h>
#include <viewcells/io/scene_io.h>
#include <viewcells/q3/bsp_file.h>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: scene_stats SCENE\n";
    return 2;
  }
  try {
    viewcells::register_q3_map_format();  // .bsp files read too
    const viewcells::Scene scene = viewcells::load_scene(argv[1]);
    std::cout << scene.object_count() << " objects, " << scene.triangle_count() << " triangles\n";
  } catch (const viewcells::Error& e) {
    std::cerr << "scene_stats: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
