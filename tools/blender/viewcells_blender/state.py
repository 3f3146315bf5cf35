"""What the add-on's modules share: the names of what it puts in a scene, and this session's
bakes."""

CELLS_COLLECTION = "viewcells cells"
PLAY_COLLECTION = "viewcells play space"
CELL_MATERIAL = "viewcells cell"
baked = {}  # .pvs path (absolute) -> viewcells.Baked of this session
job = None  # the bake running in the background (a modal run from the panel)
last_stages = []  # the progress values the last background bake went through, in order
