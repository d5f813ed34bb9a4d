"""Where a video frame's overlays go (the legend, the caption, the label), in pixels:
each in the first corner of its preference that covers neither the start nor the goal
cell (projected through the frame's camera) nor an overlay placed before it. Geometry
only; experiments.outputs.rendering draws them."""
import numpy as np

#: The legend's layout in pixels: margin, row height, swatch size, panel width.
LEGEND_BOX = (10, 26, 16, 190)
#: Each overlay's corners of the frame, in order of preference.
PREFERENCES = {"legend": ("bottom right", "bottom left", "top right", "top left"),
               "caption": ("top left", "top right", "bottom left", "bottom right"),
               "label": ("bottom left", "bottom right", "top left", "top right")}
#: MuJoCo's grid position of a text overlay (mjr_overlay) in each corner.
GRID = {"top left": 0, "top right": 1, "bottom left": 2, "bottom right": 3}  # mjtGridPos
#: mjr_overlay's padding around a text (MuJoCo's render_gl2.c: PAD, and 8 more pixels
#: of width), and the pixels kept clear around the start and goal cells.
TEXT_PAD, CLEARANCE = 5, 3


def legend_size(n):
    """(width, height) of the legend's panel of n rows, in pixels."""
    _, row, _, panel = LEGEND_BOX
    return panel, n * row + 8


def text_size(context, text):
    """(width, height) in pixels of the box mjr_overlay draws behind one line of text in
    MuJoCo's normal font, as render_gl2.c sizes it."""
    width = sum(int(context.charWidth[min(ord(c), 255)]) for c in text)
    return TEXT_PAD + width + 8, TEXT_PAD + int(context.charHeight)


def box_at(name, corner, size, height, width):
    """The (left, bottom, right, top) pixels, from the frame's bottom left, of overlay
    `name` ("legend", "caption" or "label") of size (w, h) in `corner`: the legend at
    LEGEND_BOX's margin, a text where mjr_overlay puts it."""
    w, h = size
    if name == "legend":
        margin = LEGEND_BOX[0]
        left = width - w - margin if corner.endswith("right") else margin
        bottom = margin - 4 if corner.startswith("bottom") else height - (margin - 4) - h
    else:
        left = width - 1 - TEXT_PAD - w if corner.endswith("right") else TEXT_PAD
        bottom = TEXT_PAD if corner.startswith("bottom") else height - 1 - TEXT_PAD - h
    return left, bottom, left + w, bottom + h


def _overlap(a, b):
    """The area two (left, bottom, right, top) boxes share."""
    return max(0, min(a[2], b[2]) - max(a[0], b[0])) * max(0, min(a[3], b[3]) - max(a[1], b[1]))


def place(sizes, keep_out, height, width):
    """{overlay name: corner} for the overlays of sizes ({name: (w, h) or None}): each,
    the legend first, in the first corner of its PREFERENCES where it covers no box of
    keep_out (the start and goal cells, grown by CLEARANCE) and no overlay placed before
    it; where every corner covers something, the one that covers least."""
    clear = [(x0 - CLEARANCE, y0 - CLEARANCE, x1 + CLEARANCE, y1 + CLEARANCE)
             for x0, y0, x1, y1 in keep_out]
    placed, corners = [], {}
    for name in ("legend", "caption", "label"):
        if not sizes.get(name):
            continue
        options = PREFERENCES[name]

        def cost(corner):
            box = box_at(name, corner, sizes[name], height, width)
            covered = sum(_overlap(box, k) for k in clear) + sum(_overlap(box, p) for p in placed)
            return covered > 0, covered, options.index(corner)

        corners[name] = min(options, key=cost)
        placed.append(box_at(name, corners[name], sizes[name], height, width))
    return corners


def landmarks(physics):
    """The start cell's and the goal cell's corners on the floor, in metres: the goal
    site covers its cell; the start cell is a cell of that size around the start site."""
    m = physics.model
    goal, start = m.site("goal"), m.site("start")
    hx, hy = goal.size[:2]
    return [np.array([(c[0] + dx, c[1] + dy, c[2]) for dx in (-hx, hx) for dy in (-hy, hy)])
            for c in (start.pos, goal.pos)]


def project(camera, points, height, width):
    """(x, y) pixels, from the frame's bottom left, of world points (metres) seen by an
    mjvGLCamera (the scene's, as mjr_render draws it: a frustum of zero width takes the
    frame's aspect ratio); None when a point is not in front of the camera."""
    pos, forward, up = (np.asarray(v, dtype=np.float64) for v in (camera.pos, camera.forward, camera.up))
    right = np.cross(forward, up)
    rel = np.asarray(points, dtype=np.float64) - pos
    x, y, z = rel @ right, rel @ up, rel @ forward
    if not camera.orthographic:
        if (z <= camera.frustum_near).any():
            return None
        x, y = camera.frustum_near * x / z, camera.frustum_near * y / z
    bottom, top = camera.frustum_bottom, camera.frustum_top
    half = camera.frustum_width or 0.5 * width / height * (top - bottom)
    left = camera.frustum_center - half
    return np.stack([(x - left) / (2 * half) * width, (y - bottom) / (top - bottom) * height], axis=1)


def landmark_boxes(physics, scene, height, width):
    """The (left, bottom, right, top) pixel boxes of the start and goal cells on a frame
    of scene (after mjv_updateScene), clipped to the frame; a cell out of view or behind
    the camera has none."""
    import mujoco
    camera = mujoco.mjv_averageCamera(scene.camera[0], scene.camera[1])
    boxes = []
    for corners in landmarks(physics):
        xy = project(camera, corners, height, width)
        if xy is None:
            continue
        (x0, y0), (x1, y1) = np.floor(xy.min(axis=0)), np.ceil(xy.max(axis=0))
        x0, y0, x1, y1 = max(x0, 0), max(y0, 0), min(x1, width), min(y1, height)
        if x0 < x1 and y0 < y1:
            boxes.append((int(x0), int(y0), int(x1), int(y1)))
    return boxes


def legend_swatches(height, width, n, corner="bottom right"):
    """The swatch rectangle (left, bottom, width, height) of each of n legend rows, in
    pixels from the frame's bottom left, top row first, with the legend in `corner` of
    a (height, width) frame (bottom right unless it would cover the start or the goal)."""
    _, row, swatch, _ = LEGEND_BOX
    left, bottom, _, _ = box_at("legend", corner, legend_size(n), height, width)
    return [(left + 8, bottom + 4 + (n - 1 - i) * row + (row - swatch) // 2, swatch, swatch)
            for i in range(n)]
