"""Rooms as maps: a text map in labmaze's convention, made into the room's MJCF.

A map is rows of cells, the top row first, each `*` (a wall), a space (free), `P` (the
start cell: one) or `G` (the goal cell: one); every row the same length, and the border
all walls (labmaze's mazes and Gymnasium-Robotics' maps have one). Lines starting with
`#` are comments; `# cell N` sets the cell's side in paper units (default the paper's 10);
`# walls NAME ...` names the merged inner walls in their order (default block_0, ...).

`load(room)` takes a shipped map's name (`MAPS`: `sutton`, the paper's room, the
default; Gymnasium-Robotics' `u_maze`, `medium`, `large`), `random:WxH:SEED` (a
labmaze.RandomMaze of W x H inner cells, `random_map`), or a map file. `room_xml(map)`
writes the room: the floor under the inner cells, the border as four outer walls (west
and east the full height, south and north between them), the inner walls merged into
few boxes (`merged_walls`), the goal site over the goal cell, the start site at the
start cell's centre heading to its first free neighbour (east, north, west, south), the
cameras framing the whole room. The paper's room is `sutton`'s, bit for bit the room the
golden data were made in (tests/test_rooms.py, tests/data/make_golden.py; docs/rooms.md).
Coordinates: the inner cells' lower-left corner is the world origin, x east, y north.
"""
from __future__ import annotations

import collections
import dataclasses
import functools
import pathlib
import re

import numpy as np

#: The paper's cell: 10 units (Section 3.1: a 9 x 6 grid of 10-unit cells).
CELL = 10.0
#: The walls' height in units (0.3 m at the paper's unit).
WALL_HEIGHT = 3.0
#: The room every command uses unless told another.
DEFAULT = "sutton"
MAP_DIR = pathlib.Path(__file__).resolve().parent / "maps"
#: The shipped maps, by name: (file, what it is).
MAPS = {
    "sutton": "the paper's room: Sutton's Dyna maze, 9 x 6 cells (Unemi 2000, Figure 1)",
    "u_maze": "Gymnasium-Robotics' U_MAZE (PointMaze_UMaze), 3 x 3 cells",
    "medium": "Gymnasium-Robotics' MEDIUM_MAZE (PointMaze_Medium), 6 x 6 cells",
    "large": "Gymnasium-Robotics' LARGE_MAZE (PointMaze_Large), 10 x 7 cells",
}
#: random:WxH:SEED
RANDOM = re.compile(r"random:(\d+)x(\d+):(\d+)$")
#: The random mazes' sizes, in inner cells.
RANDOM_SIZES = (3, 31)
#: The random mazes' seeds: labmaze's (a signed 32-bit integer, from 0).
RANDOM_SEEDS = (0, 2**31 - 1)
#: A room's widest side in units: runs store positions as int16 hundredths of a unit
#: (experiments.running.execution.TRACE_SCALE), at most 327.67.
MAX_EXTENT = 320.0
WALL, FREE, START, GOAL = "*", " ", "P", "G"


class MapError(ValueError):
    """A map that cannot be a room; the message names the map (its file) and what is wrong."""


@dataclasses.dataclass(frozen=True)
class Map:
    """A parsed map: rows top first, border included; cell: a cell's side in units."""
    name: str
    rows: tuple[str, ...]
    cell: float = CELL
    #: What an error names: the map's file, or its name.
    source: str = ""
    #: The merged inner walls' geom names, in merged_walls' order (() : block_0, ...).
    wall_names: tuple[str, ...] = ()

    @property
    def width(self) -> int:
        """Inner cells west to east."""
        return len(self.rows[0]) - 2

    @property
    def height(self) -> int:
        """Inner cells south to north."""
        return len(self.rows) - 2

    def cell_of(self, char) -> tuple[int, int]:
        """(column, row) of the one cell holding char, inner cells, row 0 the south."""
        for r, row in enumerate(self.rows):
            if char in row:
                return row.index(char) - 1, len(self.rows) - 2 - r
        raise MapError(f"{self.source}: no {char!r} cell")

    def wall(self, col, row) -> bool:
        """True where the inner cell (col, row; row 0 the south) is a wall; the border is."""
        if not (0 <= col < self.width and 0 <= row < self.height):
            return True
        return self.rows[len(self.rows) - 2 - row][col + 1] == WALL

    @property
    def start(self):
        return self.cell_of(START)

    @property
    def goal(self):
        return self.cell_of(GOAL)

    @property
    def start_heading(self) -> float:
        """The start's heading (rad): towards its first open neighbour of east, north,
        west, south."""
        sc, sr = self.start
        return next((a for a, (dc, dr) in zip((0.0, np.pi / 2, np.pi, -np.pi / 2),
                                              ((1, 0), (0, 1), (-1, 0), (0, -1)))
                     if not self.wall(sc + dc, sr + dr)), 0.0)

    def text(self) -> str:
        """The map as a map file's text (its cell exact: 10, 0.001953125)."""
        cell = f"{self.cell:g}" if float(f"{self.cell:g}") == self.cell else repr(self.cell)
        return f"# cell {cell}\n" + "\n".join(self.rows) + "\n"

    def shortest_cells(self) -> int:
        """The fewest cell moves (4-neighbour) from the start cell to the goal cell."""
        return reachable(self)[self.goal]


def reachable(m: Map) -> dict[tuple[int, int], int]:
    """{free inner cell reachable from the start: its cell moves from the start}."""
    seen = {m.start: 0}
    queue = collections.deque([m.start])
    while queue:
        c, r = queue.popleft()
        for dc, dr in ((1, 0), (0, 1), (-1, 0), (0, -1)):
            n = (c + dc, r + dr)
            if n not in seen and not m.wall(*n):
                seen[n] = seen[(c, r)] + 1
                queue.append(n)
    return seen


def parse(text: str, source: str, name: str | None = None) -> Map:
    """The Map of a map's text (a UTF-8 byte-order mark before it is ignored); MapError
    naming source and what is wrong."""
    cell, rows, names = CELL, [], ()
    for number, line in enumerate(text.removeprefix("\ufeff").splitlines(), 1):
        if line.startswith("#"):
            words = line[1:].split()
            if words[:1] == ["walls"]:
                names = tuple(words[1:])
            if words[:1] == ["cell"]:
                try:
                    cell = float(words[1])
                    if not (np.isfinite(cell) and cell > 0):
                        raise ValueError
                except (IndexError, ValueError):
                    raise MapError(f"{source}: line {number}: '# cell' needs a positive "
                                   f"number of paper units, got {line!r}") from None
            continue
        if not line.strip() and not rows:
            continue
        rows.append((number, line))
    while rows and not rows[-1][1].strip():
        rows.pop()
    if not rows:
        raise MapError(f"{source}: no map rows")
    widths = {len(line) for _, line in rows}
    if len(widths) > 1:
        number, line = next((n, s) for n, s in rows if len(s) != len(rows[0][1]))
        raise MapError(f"{source}: not a rectangle: line {number} has {len(line)} cells, "
                       f"the first row {len(rows[0][1])}")
    for number, line in rows:
        bad = set(line) - {WALL, FREE, START, GOAL}
        if bad:
            raise MapError(f"{source}: line {number}: unknown character {sorted(bad)[0]!r} "
                           f"(a map has '*' walls, ' ' free cells, one 'P' start, one 'G' goal)")
    if len(rows) < 3 or len(rows[0][1]) < 3:
        raise MapError(f"{source}: a map needs at least 3 x 3 cells, border included")
    last = len(rows) - 1
    for i, (number, line) in enumerate(rows):
        edge = line if i in (0, last) else line[0] + line[-1]
        if set(edge) != {WALL}:
            raise MapError(f"{source}: line {number}: the border must be all walls ('*')")
    for char, what in ((START, "start"), (GOAL, "goal")):
        count = sum(line.count(char) for _, line in rows)
        if count != 1:
            raise MapError(f"{source}: {'no' if not count else count} {char!r} cells: "
                           f"a map has one {what}")
    m = Map(name or pathlib.Path(source).stem, tuple(line for _, line in rows), cell, source,
            names)
    if max(m.width, m.height) * cell > MAX_EXTENT:
        raise MapError(f"{source}: {m.width} x {m.height} cells of {cell:g} units is wider "
                       f"than the {MAX_EXTENT:g} units a run's trace holds")
    if m.goal not in reachable(m):
        raise MapError(f"{source}: the goal cannot be reached from the start")
    if names and len(names) != len(merged_walls(m)):
        raise MapError(f"{source}: '# walls' names {len(names)} walls; the map's inner walls "
                       f"merge into {len(merged_walls(m))}")
    return m


def random_map(width: int, height: int, seed: int) -> Map:
    """A labmaze.RandomMaze of width x height inner cells (its defaults, the seed's).

    labmaze draws odd sizes only: an even side is drawn one cell larger and one of its
    wall lines removed (labmaze's corridors lie on odd lines, its walls on even ones: the
    column before the eastmost corridor column, the row below the northmost corridor row).
    Free cells the start cannot reach become walls. The start is the free cell nearest
    the south-west corner (the westmost column, then the southmost row); the goal, the
    free cell farthest from it in cell moves (ties: the southmost, then the eastmost)."""
    import labmaze
    lo, hi = RANDOM_SIZES
    if not (lo <= width <= hi and lo <= height <= hi):
        raise MapError(f"random:{width}x{height}:{seed}: sizes must be {lo}..{hi} cells")
    if not RANDOM_SEEDS[0] <= seed <= RANDOM_SEEDS[1]:
        raise MapError(f"random:{width}x{height}:{seed}: the seed must be {RANDOM_SEEDS[0]}.."
                       f"{RANDOM_SEEDS[1]} (labmaze's seeds are 32-bit)")
    w, h = width + (width % 2 == 0), height + (height % 2 == 0)
    maze = labmaze.RandomMaze(height=h + 2, width=w + 2, random_seed=int(seed))
    grid = [list(line) for line in str(maze.entity_layer).splitlines()]
    grid = [[WALL if ch == WALL else FREE for ch in row] for row in grid]
    if w != width:  # grid column w is the eastmost corridor column; w - 1 a wall line
        grid = [row[:w - 1] + row[w:] for row in grid]
    if h != height:  # grid row 1 is the northmost corridor row; row 2 a wall line
        grid = grid[:2] + grid[3:]
    name = f"random:{width}x{height}:{seed}"
    free = [(c - 1, len(grid) - 2 - r) for r, row in enumerate(grid)
            for c, ch in enumerate(row) if ch == FREE]
    if not free:
        raise MapError(f"{name}: labmaze drew no free cell")
    start = min(free)
    rows = ["".join(row) for row in grid]
    m = Map(name, tuple(_put(rows, start, START)), CELL, name)
    distance = reachable(m)
    for c, r in free:
        if (c, r) not in distance:
            rows = _put(rows, (c, r), WALL)
    goal = max(distance, key=lambda cr: (distance[cr], -cr[1], cr[0]))
    if goal == start:
        raise MapError(f"{name}: labmaze drew a single free cell")
    rows = _put(_put(rows, start, START), goal, GOAL)
    return Map(name, tuple(rows), CELL, name)


def _put(rows, cell, char):
    c, r = cell
    rows = list(rows)
    i = len(rows) - 2 - r
    rows[i] = rows[i][:c + 1] + char + rows[i][c + 2:]
    return rows


def load(room: str | pathlib.Path | Map | None = None) -> Map:
    """The Map of a room: a Map, a shipped map's name, random:WxH:SEED, or a map file."""
    if isinstance(room, Map):
        return room
    room = DEFAULT if room is None else str(room)
    if room in MAPS:
        return _shipped(room)
    found = RANDOM.match(room)
    if found:
        return random_map(*(int(g) for g in found.groups()))
    path = pathlib.Path(room)
    if not path.is_file():
        raise MapError(f"no room {room!r}: a shipped map ({', '.join(MAPS)}), "
                       "random:WxH:SEED, or a map file")
    try:
        text = path.read_bytes().decode("utf-8")
    except OSError as e:
        raise MapError(f"{path}: cannot read: {e.strerror or e}") from None
    except UnicodeDecodeError as e:
        raise MapError(f"{path}: not a UTF-8 text file (byte {e.start})") from None
    return parse(text, str(path))


_cache: dict[str, Map] = {}


def _shipped(name):
    if name not in _cache:
        path = MAP_DIR / f"{name}.txt"
        _cache[name] = parse(path.read_text(), str(path), name)
    return _cache[name]


def tag(room) -> str:
    """The room's name in folders and tables: a shipped map's name, random-WxH-SEED,
    or a map file's stem."""
    text = room.name if isinstance(room, Map) else str(DEFAULT if room is None else room)
    if text in MAPS or RANDOM.match(text):
        return text.replace(":", "-")
    return pathlib.Path(text).stem


def check_fits(m: Map, radius: float) -> None:
    """MapError when a corridor (one cell) is narrower than the robot (radius in units)."""
    if m.cell <= 2 * radius:
        raise MapError(f"{m.source}: corridors of {m.cell:g} units are narrower than the "
                       f"robot ({2 * radius:.3g} units across); set '# cell N' larger")


def merged_walls(m: Map) -> list[tuple[int, int, int, int]]:
    """The inner walls as few boxes (c0, c1, r0, r1: cells c0..c1-1, r0..r1-1): the
    largest rectangle of walls not yet covered, again and again; sorted west to east,
    then south to north."""
    left = np.array([[m.wall(c, r) for c in range(m.width)] for r in range(m.height)], bool)
    boxes = []
    while left.any():
        boxes.append(_largest_rectangle(left))
        c0, c1, r0, r1 = boxes[-1]
        left[r0:r1, c0:c1] = False
    return sorted(boxes)


def _largest_rectangle(grid):
    """(c0, c1, r0, r1) of the largest all-True rectangle (the histogram method); ties:
    the first found, rows south to north."""
    best, best_area = None, 0
    heights = np.zeros(grid.shape[1], int)
    for r in range(grid.shape[0]):
        heights = np.where(grid[r], heights + 1, 0)
        stack = []  # columns of rising heights
        for c in range(grid.shape[1] + 1):
            h = heights[c] if c < grid.shape[1] else 0
            start = c
            while stack and stack[-1][1] > h:
                start, top = stack.pop()
                area = top * (c - start)
                if area > best_area:
                    best, best_area = (start, c, r - top + 1, r + 1), area
            if not stack or stack[-1][1] < h:
                stack.append((start, h))
    return best


def _f(value):
    """A length in metres as MJCF text, without the float noise of unit arithmetic."""
    return format(float(value), ".10g")


def _vec(*values):
    return " ".join(_f(v) for v in values)


@functools.lru_cache(maxsize=64)
def layout(room=None):
    """(field, obstacles, goal, start) of a room, in paper units, from its Map: field and
    goal (x0, x1, y0, y1), the merged inner walls as rectangles (merged_walls' order),
    the start (x, y, heading) at its cell's centre. What room_xml builds the room from,
    so figures and the optimal path draw the room the robots run in without compiling
    it (models.room_layout reads a compiled room back, as the task's Physics does)."""
    m = load(room)
    c = m.cell
    walls = [(c0 * c, c1 * c, r0 * c, r1 * c) for c0, c1, r0, r1 in merged_walls(m)]
    (gc, gr), (sc, sr) = m.goal, m.start
    return ((0.0, m.width * c, 0.0, m.height * c), walls,
            (gc * c, (gc + 1) * c, gr * c, (gr + 1) * c),
            ((sc + 0.5) * c, (sr + 0.5) * c, m.start_heading))


def room_xml(room=None) -> str:
    """The room's MJCF, at the paper's unit (models.UNIT metres per paper unit;
    models.scale_room scales it for a robot of another unit)."""
    from models import UNIT as unit
    m = load(room)
    cell = m.cell * unit
    w, h = m.width * cell, m.height * cell
    half = WALL_HEIGHT * unit / 2
    # The paper's room (9 x 6 m) frames with these cameras; a larger room, from farther.
    s = max(w / 9.0, h / 6.0)
    walls = [("wall_west", "wall", (-cell / 2, h / 2), (cell / 2, h / 2 + cell)),
             ("wall_east", "wall", (w + cell / 2, h / 2), (cell / 2, h / 2 + cell)),
             ("wall_south", "wall", (w / 2, -cell / 2), (w / 2, cell / 2)),
             ("wall_north", "wall", (w / 2, h + cell / 2), (w / 2, cell / 2))]
    for i, (c0, c1, r0, r1) in enumerate(merged_walls(m)):
        name = m.wall_names[i] if m.wall_names else f"block_{i}"
        walls.append((name, "obstacle", ((c0 + c1) * cell / 2, (r0 + r1) * cell / 2),
                      ((c1 - c0) * cell / 2, (r1 - r0) * cell / 2)))
    geoms = "\n".join(
        f'    <geom name="{name}" class="{cls}" pos="{_vec(*pos, half)}"'
        f' size="{_vec(*size, half)}"/>' for name, cls, pos, size in walls)
    (gc, gr), (sc, sr) = m.goal, m.start
    heading = m.start_heading
    orient = "" if heading == 0.0 else f' euler="0 0 {_f(heading)}"'
    texrepeat = _vec(m.width * m.cell / CELL, m.height * m.cell / CELL)
    goal = (f'pos="{_vec((gc + 0.5) * cell, (gr + 0.5) * cell, 0.002)}" '
            f'size="{_vec(cell / 2, cell / 2, 0.002)}"')
    start = (f'pos="{_vec((sc + 0.5) * cell, (sr + 0.5) * cell, 0.002)}"{orient} '
             f'size="{_vec(3 * unit, 3 * unit, 0.002)}"')
    return f"""<mujoco model="{m.name}_room">
  <compiler angle="radian"/>
  <!-- Gravity is on: 3D robots stand and roll on the floor. The planar robots' joints
       (slide x, slide y, hinge yaw) are horizontal, so gravity does no work on them.
       Semi-implicit Euler at 0.05 s is the planar robots' setting: their velocity servos
       are tuned at load time to reach their target in one step (kv = mass / timestep),
       which an implicit integrator would turn into a heavier body that contacts cannot
       stop. A robot's registry entry may set its own timestep and integrator. -->
  <option timestep="0.05" integrator="Euler" gravity="0 0 -9.81"/>
  <size memory="2M"/>
  <visual>
    <global offwidth="960" offheight="640"/>
    <quality shadowsize="0"/>
    <headlight ambient="0.5 0.5 0.5" diffuse="0.5 0.5 0.5"/>
  </visual>
  <default>
    <!-- Stiff walls: solref's time constant is clamped to two timesteps, so a contact
         removes the approach speed within one step. A robot's bumper brings its own
         contact parameters; where both sides agree, MuJoCo's mix is exactly these. -->
    <geom contype="1" conaffinity="1" condim="1" solref="0.02 1" solimp="0.99 0.999 0.001 0.5 2"/>
    <default class="wall">
      <geom type="box" rgba="0.35 0.35 0.4 1"/>
    </default>
    <default class="obstacle">
      <geom type="box" rgba="0.55 0.45 0.35 1"/>
    </default>
    <default class="marker">
      <site type="box" group="0"/>
    </default>
  </default>
  <asset>
    <texture name="grid" type="2d" builtin="checker" width="64" height="64"
             rgb1="0.93 0.93 0.93" rgb2="0.86 0.86 0.86"/>
    <material name="grid" texture="grid" texrepeat="{texrepeat}"/>
  </asset>
  <worldbody>
    <light pos="{_vec(w / 2, h / 2, 8 * s)}" dir="0 0 -1" directional="true"/>
    <!-- Looks straight down at the room's centre; a 3:2 image frames the whole room. -->
    <camera name="top" pos="{_vec(w / 2, h / 2, 8.6 * s)}" xyaxes="1 0 0 0 1 0" fovy="45"/>
    <!-- From above the south wall, looking north and down: shows robots in 3D. -->
    <camera name="perspective" pos="{_vec(w / 2, -1.3 * s, 6.7 * s)}"
            xyaxes="1 0 0 0 0.866 0.5" fovy="45"/>
    <!-- The floor collides on its own bit (contype 4): only geoms that opt in with
         conaffinity 4 (wheels, casters, skids) touch it; bumpers (2 / 1) never do, so the
         planar robots glide on their joints. See models/__init__.py. -->
    <geom name="floor" type="plane" size="{_vec(w / 2, h / 2, 0.1)}" pos="{_vec(w / 2, h / 2, 0)}"
          material="grid" contype="4" conaffinity="0"/>
    <!-- The border: outer walls one cell thick outside the field; then the inner walls. -->
{geoms}
    <!-- Markers are sites, so rangefinders never see them. -->
    <site name="goal" class="marker" {goal} rgba="0.2 0.75 0.3 0.6"/>
    <site name="start" class="marker" {start} rgba="0.3 0.45 0.9 0.35"/>
  </worldbody>
</mujoco>
"""
