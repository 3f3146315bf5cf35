"""The bake's keywords from the panel's settings and extra option words, and the progress
bar's stages from the bake's log lines."""
import shlex


def option_words(text):
    """Extra `viewcells bake` options written as on the command line ("--samples 30000 --no-ga")
    as keywords for viewcells.bake."""
    words = shlex.split(text)
    out = {}
    i = 0
    while i < len(words):
        w = words[i]
        if not w.startswith("--") or len(w) < 3:
            raise ValueError(f"extra options: '{w}' is not an option (write them as --name value)")
        key = w[2:].replace("-", "_")
        if i + 1 < len(words) and not words[i + 1].startswith("--"):
            out[key] = words[i + 1]
            i += 2
        else:
            out[key] = True
            i += 1
    return out


def bake_options(settings):
    """The bake's keywords from the panel's settings, as `viewcells bake` takes them."""
    o = {}
    if settings.budget == "CELLS":
        o["cells"] = settings.cells
    else:
        o["memory"] = settings.memory
    if settings.holes > 0:
        o["holes"] = f"{settings.holes:g}%"
    if settings.pixel_error > 0:
        o["pixel_error"] = settings.pixel_error
    if settings.time > 0:
        o["time"] = settings.time
    o.update(option_words(settings.extra))
    return o


STAGES = [("loaded", 0.03), ("sampling", 0.05), ("valid segments", 0.15), ("subdividing", 0.2),
          ("cells in", 0.35), ("merging", 0.4), ("leaf PVSs", 0.5), ("by AGVS", 0.55), ("view cells, mean", 0.95)]


def progress_of(line, previous):
    for key, value in STAGES:
        if key in line:
            return max(previous, value)
    return previous
