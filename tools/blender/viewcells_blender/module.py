"""The Python module `viewcells`: where the add-on finds it."""
import os
import sys

import bpy


def import_viewcells():
    """The module `viewcells`, from sys.path, $VIEWCELLS_PYTHONPATH, the add-on's preferences or
    the checkout's build/python. Raises ImportError saying where it looked."""
    try:
        import viewcells  # noqa: F401
        return sys.modules["viewcells"]
    except ImportError:
        pass
    here = os.path.dirname(os.path.realpath(__file__))  # through the link install-blender-addon.sh makes
    places = [os.environ.get("VIEWCELLS_PYTHONPATH", "")]
    addon = bpy.context.preferences.addons.get(__name__)
    if addon is not None:
        places.append(bpy.path.abspath(addon.preferences.module_dir))
    places.append(os.path.normpath(os.path.join(here, "..", "..", "..", "build", "python")))
    for place in places:
        if place and os.path.isdir(place) and place not in sys.path:
            sys.path.append(place)
            try:
                import viewcells  # noqa: F401
                return sys.modules["viewcells"]
            except ImportError:
                sys.path.remove(place)
    raise ImportError("the Python module viewcells was not found (looked on sys.path and in "
                      + ", ".join(p for p in places if p)
                      + "); build it (scripts/test.sh or -DVIEWCELLS_PYTHON=ON) and set its directory in "
                      "the add-on's preferences or $VIEWCELLS_PYTHONPATH")


# ---------------------------------------------------------------------------------------------
# Blender's meshes as a scene
