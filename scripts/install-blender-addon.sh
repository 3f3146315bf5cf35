#!/usr/bin/env bash
# Installs the Blender add-on (tools/blender/viewcells_blender) for this user, by a link into
# Blender's add-on directory, and enables it. The add-on finds the Python module in this
# checkout's build/python (scripts/test.sh or scripts/build.sh with -DVIEWCELLS_PYTHON=ON build
# it). Idempotent; `--remove` takes the link away.
set -euo pipefail
cd "$(dirname "$0")/.."
blender=${BLENDER:-blender}
command -v "$blender" >/dev/null || { echo "install-blender-addon: blender not found (scripts/install-deps.sh installs it)" >&2; exit 1; }
version=$("$blender" -b --factory-startup --python-expr 'import bpy; print("VERSION", "%d.%d" % bpy.app.version[:2])' 2>/dev/null | awk '/^VERSION/ {print $2}')
[ -n "$version" ] || { echo "install-blender-addon: could not ask $blender for its version" >&2; exit 1; }
addons="${XDG_CONFIG_HOME:-$HOME/.config}/blender/$version/scripts/addons"
link="$addons/viewcells_blender"
if [ "${1:-}" = "--remove" ]; then
  rm -f "$link"
  echo "install-blender-addon: removed $link"
  exit 0
fi
ls build/python/viewcells*.so >/dev/null 2>&1 || echo "install-blender-addon: note: build/python has no module yet; run scripts/test.sh first" >&2
mkdir -p "$addons"
ln -sfn "$PWD/tools/blender/viewcells_blender" "$link"
"$blender" -b --python-expr 'import addon_utils, bpy; addon_utils.enable("viewcells_blender", default_set=True, handle_error=None); bpy.ops.wm.save_userpref()' >/dev/null
echo "install-blender-addon: $link -> tools/blender/viewcells_blender, enabled in Blender $version (3D View > Sidebar > viewcells)"
