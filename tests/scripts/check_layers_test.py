"""tools/check-layers.py: an include that runs up the layers, or across to a layer beside, is
named with its file and line and fails; the library itself passes."""
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
CHECK = os.path.join(HERE, "..", "..", "tools", "check-layers.py")
LIBRARY = os.path.join(HERE, "..", "..", "libviewcells")

CMAKE = """
vc_layer(base
  src/base/a.cpp)
vc_layer(left
  src/left/b.cpp BELOW base)
vc_layer(right
  src/right/c.cpp BELOW base)
vc_layer(top
  src/top/d.cpp BELOW left right)
"""


def tree(files):
    root = tempfile.mkdtemp()
    with open(os.path.join(root, "CMakeLists.txt"), "w") as f:
        f.write(CMAKE)
    for path, text in files.items():
        full = os.path.join(root, path)
        os.makedirs(os.path.dirname(full), exist_ok=True)
        with open(full, "w") as f:
            f.write(text)
    return root


def check(root):
    return subprocess.run([sys.executable, CHECK, root], capture_output=True, text=True)


class CheckLayers(unittest.TestCase):
    def test_down_and_format_pass(self):
        r = check(tree({"src/top/d.cpp": '#include "viewcells/left/b.h"\n#include "base/x.h"\n',
                        "src/left/b.cpp": '#include "viewcells/base/a.h"\n#include "viewcells/format/id_lists.h"\n',
                        "include/viewcells/right/c.h": '#include "viewcells/base/a.h"\n#include "local.h"\n'}))
        self.assertEqual(r.returncode, 0, r.stdout)

    def test_up_fails_with_file_and_line(self):
        r = check(tree({"src/base/a.cpp": '// a\n#include "viewcells/top/d.h"\n'}))
        self.assertEqual(r.returncode, 1)
        self.assertIn(os.path.join("src", "base", "a.cpp") + ":2: layer base includes viewcells/top/d.h of layer top",
                      r.stdout)

    def test_beside_fails(self):
        r = check(tree({"include/viewcells/left/b.h": '#include "right/c.h"\n'}))
        self.assertEqual(r.returncode, 1)
        self.assertIn("layer left includes right/c.h of layer right", r.stdout)

    def test_unknown_directory_fails(self):
        r = check(tree({"src/stray/e.cpp": "int e;\n"}))
        self.assertEqual(r.returncode, 1)
        self.assertIn("directory stray belongs to no layer", r.stdout)

    def test_the_pipeline_may_not_include_quake3(self):
        """Quake 3 is an adapter beside the pipeline: the library's own layers refuse an include
        of q3/ from pipeline/ (a copy of the library with one such include added fails)."""
        import shutil
        root = tempfile.mkdtemp()
        shutil.copytree(LIBRARY, os.path.join(root, "lib"), ignore=shutil.ignore_patterns("*.o"))
        with open(os.path.join(root, "lib", "src", "pipeline", "bake.cpp"), "a") as f:
            f.write('#include "viewcells/q3/level.h"\n')
        r = check(os.path.join(root, "lib"))
        self.assertEqual(r.returncode, 1, r.stdout)
        self.assertIn("layer pipeline includes viewcells/q3/level.h of layer q3", r.stdout)

    def test_the_library_passes(self):
        r = check(LIBRARY)
        self.assertEqual(r.returncode, 0, r.stdout)


if __name__ == "__main__":
    unittest.main()
