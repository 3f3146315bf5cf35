"""The bake's keywords from the panel's settings and extra option words, and the progress
bar's stages from the bake's log lines."""
import shlex


def option_words(text, table):
    """Extra `viewcells bake` options written as on the command line ("--samples 30000 --no-ga",
    "--start 1,2,0 --start 5,2,0") as keywords for viewcells.bake. `table` is the library's list of
    the bake's options (viewcells.bake_options()): it says which take a value, which repeat and
    which flag turns another off, so the words mean what they mean to `viewcells bake`."""
    by_name = {}
    for o in table:
        by_name[o["flag"]] = (o, True)
        if o["negation"]:
            by_name[o["negation"]] = (o, False)
    words = shlex.split(text)
    out = {}
    i = 0
    while i < len(words):
        name, eq, given = words[i].partition("=")
        if name not in by_name:
            raise ValueError(f"extra options: '{words[i]}' is not an option of viewcells bake")
        option, on = by_name[name]
        key = option["keyword"]
        if option["kind"] == "flag":
            out[key] = on if not eq else (given.lower() in ("true", "1", "on", "yes")) == on
            i += 1
            continue
        if not eq:
            if i + 1 == len(words):
                raise ValueError(f"extra options: {name} needs a value")
            given = words[i + 1]
            i += 1
        i += 1
        if option["kind"] == "texts":
            out.setdefault(key, []).append(given)
        else:
            out[key] = given
    return out


def bake_options(settings, table):
    """The bake's keywords from the panel's settings, as `viewcells bake` takes them (`table`:
    viewcells.bake_options(), for the extra words)."""
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
    o.update(option_words(settings.extra, table))
    return o


STAGES = [("loaded", 0.03), ("sampling", 0.05), ("valid segments", 0.15), ("subdividing", 0.2),
          ("cells in", 0.35), ("merging", 0.4), ("leaf PVSs", 0.5), ("by AGVS", 0.55), ("view cells, mean", 0.95)]


def progress_of(line, previous):
    for key, value in STAGES:
        if key in line:
            return max(previous, value)
    return previous
