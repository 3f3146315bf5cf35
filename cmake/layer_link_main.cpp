// The entry point of the layer link checks (libviewcells/CMakeLists.txt, layer_link_*): each
// links one layer's objects with those of the layers below it and nothing above, so that a
// call from a layer into one above it has no definition and fails to link. Never run.
int main() { return 0; }
