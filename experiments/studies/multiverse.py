"""`ebrl multiverse`: the protocol in every combination of the readings the text allows.

A factor is an open detail of the paper's text (or one the text gives two ways, where it
contradicts itself: its sentence quotes both), or a group of details read together (the
bodies' open values), with its two levels, both taken from the readings' registry
(tasks.readings) and the protocols (tasks.protocols):

- **plain** (-1): the literal protocol's value of each of its readings (tasks.protocols.
  LITERAL, the paper as written);
- **alternative** (+1): the adopted protocol's value for the robot where it differs from
  the plain one (tasks.protocols.ADOPTED); where the adopted protocol takes the plain
  reading too, the factor's own alternative (FACTORS: a value of the registry, checked
  there). A factor that changes nothing for a robot is inert there (reported).

FACTORS lists them by hand with the sentence of the paper each reads; no factor varies a
value the paper states or an equation it prints (HELD_PLAIN, each with its reason). A
reading that the adopted protocol sets apart from the literal one and no factor names
becomes a factor of its own (`factors`), so that every universe the protocols are is in
the design, and a new protocol changes the factors' levels and count without an edit
here. The design is a two-level fractional factorial of resolution V or better over the
chosen factors (experiments.studies.design); its first row is every factor plain: the
literal protocol. The current protocol (the adopted one) is the universe at each factor's
adopted level giving the adopted protocol's own values; where no row of the design is
it, it runs beside them ("current").

Every universe runs under the adopted protocol with its factors' readings set (--set,
RunSpec.overrides: every factor reading that acts on the robot and condition, so a
universe is the same runs whatever its readings that do not act there). A run's folder
is OUT/runs/<digest of its overrides>/<robot>/<condition>/seed_NNN, as `ebrl run` writes
it, so a run that several universes share is made once; each finished run also leaves
its record (experiments.studies.multiverse_records), which is what the analysis reads
and a resume skips, on this machine or another.
"""
import dataclasses
import functools
import hashlib
import json
import pathlib
import xml.etree.ElementTree as ElementTree

from experiments import paper
from experiments.running import results, runner
from experiments.studies import design
from models import UNIT
from tasks import protocols
from tasks import readings as registry
from tasks.robots import PAPER_ROBOTS, ROBOTS


@dataclasses.dataclass(frozen=True)
class Factor:
    """An open detail of the paper: its key, its words, the readings it sets on each drive
    (tasks.robots.DRIVES' names; a drive it leaves out it does not act on), its own
    alternative values where the adopted protocol takes the plain reading, and the
    sentence of the paper it reads."""
    key: str
    label: str
    readings: dict
    alternatives: tuple = ()
    sentence: str = ""

    def names(self, drive):
        return self.readings.get(drive, ())


def _both(*names):
    return {"two_wheel": names, "floating": names}


def _one(name, alternative, label, sentence):
    """A factor of one reading of both robots, keyed by the reading's name."""
    return Factor(name, label, _both(name), ((name, alternative),), sentence)


#: The factors, hand-listed (docs/interpretation.md, "The multiverse", has each with the
#: reason its alternative is a reading of the text). Every value is checked against the
#: registry (tests/test_multiverse.py). None varies a value the paper states or an
#: equation it prints; a factor read from a contradiction in the text quotes both sides.
FACTORS = (
    Factor("threshold", "eq 5's 'enough value': the policy threshold (and eq 6's cutoff)",
           _both("policy_threshold", "utility_cutoff"),
           # where the adopted protocol sets neither: protocol 6's threshold with the
           # registry's cutoff
           (("policy_threshold", 0.3), ("utility_cutoff", 1e-4)),
           'Section 2.3: "If the agent cannot find any element of enough value of the above '
           'measure, it takes random or intrinsic behavior."'),
    _one("initial_reliability", 0.0, "a new memory element's reliability",
         'Section 2.1: "Reliability of each memory element decreases in each simulation step '
         '... Reliability is modified also in the process of learning"; Section 4: "The '
         'initial values of learning variables should also be set up appropriately"'),
    _one("eq7_signal", "surprise_measure",
         "eq 7's r: the reward as printed, or the reward less the expected one as the "
         "sentence before it says (the text contradicts itself)",
         'Section 2.4, the sentence before eq 7: "the reliability of memory element that the '
         'agent referred for decision should be modified according to the difference between '
         'real and expected reward values"; against it, eq 7 as printed: "rho r_t (1 - R_i)" '
         'with r_t eq 6\'s "current reward"'),
    _one("eq7_scope", "decided_only",
         "eq 7 walks to the episode's start, or changes deciding elements only",
         'Section 2.4: "the reliability of memory element that the agent referred for decision '
         'should be modified"'),
    _one("forgetting_link", "cut", "forgetting joins the episode across the gap, or cuts it",
         'Section 2.1: "An episode is a sequence of memory elements ... it forgets a memory '
         'element of the lowest reliability"'),
    _one("recall_candidates", "past", "recall candidates: every element, or earlier trials' only",
         'Section 2.2: "the other memory elements similar to the current sensory input are also '
         'candidates of recall table elements"'),
    _one("exploration", "random", "an exploration step: the fallback's action, or a random action",
         'Section 2.3: "it should sometimes do a type of exploration behavior ignoring the above '
         'decision process"'),
    _one("random_in_avoidance", "add",
         "the 20% random action replaces, or is added to, avoidance",
         'Section 3.4: "We should introduce some probability of random action to avoid this '
         'drawback. Here we set the probability to be 20%"'),
    Factor("body", "the bodies' open values: the plain body, or the adopted (fitted) one",
           {"two_wheel": ("radius", "leftover_turn"),
            "floating": ("radius", "action_noise", "velocity_noise", "velocity_code")},
           # where the adopted two-wheel body is the plain one: the rest turned away
           (("leftover_turn", "away"),),
           'Section 3.3: "the rest portion of move is transferred into the angle of turn" '
           '(which way, not given); the radius, the floating robot\'s action noise and its '
           'velocity sensing ("it can also detect the velocity") are not given'),
    _one("eq9_dead_zone", "zero", "eq 9's 'not changed': the previous acceleration kept, or "
         "none", 'Section 3.4, eq 9: "not changed, otherwise"'),
    _one("thrust", "demand",
         "the floating robot's velocity change for a demand a: 0.2 a (the stated maximum), "
         "or a itself (the example; the text contradicts itself)",
         'Section 3.3: "We set the maximum value of acceleration as 0.2 units per square '
         'step"; against it, its example: "the action demand (-0.2, 0.3) means that the '
         'horizontal factor of velocity decreases by 0.2 and the vertical factor of velocity '
         'increases by 0.3"'),
)

#: The readings no factor varies, each with its reason (docs/interpretation.md, "The
#: multiverse": "Held plain"): the paper states its value or prints its equation, or its
#: plain reading leaves nothing to vary. With FACTORS' readings, every reading of the
#: registry (tests/test_multiverse.py).
HELD_PLAIN = {
    "blocked_move": 'stated, Section 3.3: the robot moves until it touches and "the rest '
                    'portion of move is transferred into the angle of turn"',
    "random_demand": "stated, Section 3.4: every random action's Gaussian of sd 0.5",
    "forgetting": 'stated, Section 2.1: "it forgets a memory element of the lowest '
                  'reliability"',
    "eq7_walk": 'printed, eq 7 has no discount; "also done by following the backward links" '
                "says which elements, not a gamma",
    "bump": '"moves constantly by its own velocity until it bumps against a wall": the '
            "motion ends at the bump",
    "episode": "Section 3.6's trials each run from the start to the goal: an episode across "
               "the goal reads against them",
    "recall_at_trial_end": "keep made the same runs bit for bit as empty (protocol 5's "
                           "ablation)",
    "variance_floor": "a numerical guard (V_i = 0 divides by zero)",
    "initial_utility": "no reward seen yet",
    "wall_friction": "acts only under walls (bump=grip) the plain reading does not take",
    "restitution": "acts only under walls (bump=bounce) the plain reading does not take",
}

#: A None reading's value, for the paper's robots (the registry's "the robot file's"):
#: their files' hull radius (read from the file) and the bumper's friction, 1.
_FILE_FRICTION = 1.0


@functools.cache
def file_radius(robot):
    """The radius in units of a paper robot's hull, from its MJCF file."""
    root = ElementTree.parse(ROBOTS[robot].model).getroot()
    hull = next(g for g in root.iter("geom") if g.get("name") == "hull")
    return round(float(hull.get("size").split()[0]) / UNIT, 9)  # 0.15 m: 1.5, not 1.4999...


def effective(robot, name, value):
    """A reading's value as the robot runs it: None (the file's) as the file's number."""
    if value is None and name == "radius":
        return file_radius(robot)
    if value is None and name == "wall_friction":
        return _FILE_FRICTION
    return value


def literal_value(name):
    """The literal protocol's value of a reading (it names every reading)."""
    return dict(protocols.LITERAL.readings)[name]


def adopted_value(robot, name):
    """The adopted protocol's value of a reading for a paper robot (tasks.protocols.ADOPTED's
    readings for it, else the registry's default)."""
    entry = ROBOTS[robot]
    readings = dict(protocols.ADOPTED.readings_for(entry.name, entry.drive, entry.own_readings))
    return readings.get(name, registry.READING_BY_NAME[name].default)


def _acts(name, robot, condition=None):
    return registry.applies(registry.READING_BY_NAME[name], ROBOTS[robot], condition)


@dataclasses.dataclass(frozen=True)
class Levels:
    """A factor's two levels for one robot ({reading: value} each) and where the
    alternative comes from: "adopted", "alternative" (the factor's own) or "inert"."""
    plain: dict
    alternative: dict
    source: str


def levels(factor, robot):
    """The factor's levels for a paper robot (module docstring)."""
    names = [n for n in factor.names(ROBOTS[robot].drive) if _acts(n, robot)]
    plain = {n: literal_value(n) for n in names}
    adopted = {n: adopted_value(robot, n) for n in names}
    apart = {n for n in names if effective(robot, n, adopted[n]) != effective(robot, n, plain[n])}
    if apart:  # the adopted protocol's readings where they differ, the plain ones elsewhere
        return Levels(plain, {n: adopted[n] if n in apart else plain[n] for n in names},
                      "adopted")
    own = dict(factor.alternatives)
    alternative = {n: own.get(n, plain[n]) for n in names}
    if all(effective(robot, n, alternative[n]) == effective(robot, n, plain[n]) for n in names):
        return Levels(plain, plain, "inert")
    return Levels(plain, alternative, "alternative")


def factors():
    """FACTORS, then a factor of its own for each reading that the adopted protocol sets
    apart from the literal one on a paper robot and no factor names there."""
    out = list(FACTORS)
    named = {(d, n) for f in FACTORS for d, names in f.readings.items() for n in names}
    extra = {}
    for robot in PAPER_ROBOTS:
        drive = ROBOTS[robot].drive
        for r in registry.EVERY:
            if (drive, r.name) in named or not _acts(r.name, robot):
                continue
            if effective(robot, r.name, adopted_value(robot, r.name)) != \
                    effective(robot, r.name, literal_value(r.name)):
                extra.setdefault(r.name, []).append(drive)
    for name in sorted(extra):
        reading = registry.READING_BY_NAME[name]
        out.append(Factor(name, f"{reading.what} (set apart by the adopted protocol)",
                          {d: (name,) for d in extra[name]}, (), reading.paper))
    return tuple(out)


def select(keys=None):
    """The factors of these keys (all when None), in factors()' order; ValueError naming
    an unknown key."""
    every = factors()
    if keys is None:
        return every
    known = [f.key for f in every]
    unknown = next((k for k in keys if k not in known), None)
    if unknown is not None or not keys:
        raise ValueError(f"unknown factor {unknown or ''!r}; valid: {', '.join(known)}")
    return tuple(f for f in every if f.key in keys)


@dataclasses.dataclass(frozen=True)
class Universe:
    """One combination of the factors' levels: its name, each robot's code (+1 or -1 per
    factor of factors(), in order), its design row (None beside the design), its marks
    ("literal", "current") and, for the current protocol beside the design, adopted: its
    readings are the adopted protocol's own values (the codes say its levels): a value
    that only equals the plain one as run (the file's radius None and 1.5) need not give
    the same bits, and the current universe is the adopted protocol's runs."""
    name: str
    codes: dict
    row: int = None
    marks: tuple = ()
    adopted: bool = False

    def readings(self, robot):
        """{reading: value} of the universe's factor readings for a robot."""
        out = {}
        for factor, code in zip(factors(), self.codes[robot]):
            lv = levels(factor, robot)
            out.update(lv.alternative if code > 0 else lv.plain)
        if self.adopted:
            out = {n: adopted_value(robot, n) for n in out}
        return out

    def overrides(self, robot, condition):
        """The --set pairs of a run: the factor readings that act on robot and condition."""
        return tuple(sorted((n, v) for n, v in self.readings(robot).items()
                            if _acts(n, robot, condition)))


def current_codes(robot):
    """The adopted protocol's code of each factor for a robot: +1 where its reading is the
    adopted protocol's apart from the plain one."""
    return tuple(1 if levels(f, robot).source == "adopted" else -1 for f in factors())


def design_for(chosen):
    return design.fractional_factorial(len(chosen))


def run_order(n):
    """The order the design's rows run in: the first (every factor plain, the literal
    protocol), then the others in a fixed shuffled order, so that the first K of a partial
    run spread over every factor's levels (in the standard order the last base factor
    would stay plain for the first half)."""
    import numpy as np
    return [0] + [int(r) + 1 for r in np.random.default_rng(ORDER_SEED).permutation(n - 1)]


#: The seed of run_order's shuffle.
ORDER_SEED = 51


def universes(chosen, count=None):
    """(the design over the chosen factors, its first count universes (all when None) and
    the current protocol's universe beside them where no row of the design is it). A
    factor not chosen stays plain."""
    d = design_for(chosen)
    keys = [f.key for f in chosen]
    out = []
    for row in run_order(d.runs)[:count]:
        code = dict(zip(keys, map(int, d.matrix[row])))
        full = tuple(code.get(f.key, -1) for f in factors())
        out.append(Universe(f"u{len(out) + 1:03d}", {r: full for r in PAPER_ROBOTS}, row,
                            ("literal",) if row == 0 else ()))
    current = Universe("current", {r: current_codes(r) for r in PAPER_ROBOTS}, None,
                       ("current",), adopted=True)
    same = next((u for u in out if all(u.readings(r) == current.readings(r)
                                       for r in PAPER_ROBOTS)), None)
    if same is not None:
        out[out.index(same)] = dataclasses.replace(same, marks=same.marks + ("current",))
    else:
        out.append(current)
    return d, out


def folder_key(overrides):
    """A run setting's folder name: a digest of its overrides."""
    text = json.dumps([list(kv) for kv in overrides], sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:12]


def specs_of(universe, seeds, steps=None):
    """{(robot, condition): [RunSpec per seed]} of a universe, under the adopted protocol
    with its overrides; steps None: each robot's budget."""
    out = {}
    for robot in PAPER_ROBOTS:
        for condition in paper.CONDITIONS:
            out[(robot, condition)] = runner.plan(
                (robot,), (condition,), seeds, steps, universe.overrides(robot, condition))
    return out


def root_of(out, spec):
    return pathlib.Path(out) / "runs" / folder_key(spec.overrides)


def plan(all_universes, seeds, steps=None):
    """Every universe's runs once (a run that universes share is one spec), the longest
    first."""
    unique = {}
    for u in all_universes:
        for specs in specs_of(u, seeds, steps).values():
            unique.update(dict.fromkeys(specs))
    return sorted(unique, key=lambda s: -s.steps)


def check_on_disk(out, specs):
    """ResultsError when a run folder under OUT/runs holds a run of specs made with other
    parameters (another --steps, say), found before any work and without writing anything
    (damaged folders are left for run to set aside)."""
    runner.pending(functools.partial(root_of, out), specs, mend=False)


def run(out, specs, workers=None, backend="local", progress=True, written=None):
    """Runs the specs whose folder under OUT/runs holds no complete run (ResultsError
    first if a folder holds other runs); written(spec, run, result) after each run is
    written (its record: experiments.studies.multiverse_records). Returns runner.Ran."""
    where = functools.partial(root_of, out)
    runner.pending(where, specs)  # a damaged or mismatched folder stops it before any run
    return runner.run(specs, where, workers=workers, backend=backend, progress=progress,
                      written=written)


def failed(out, specs):
    """(run folder, error) of the specs whose run under OUT/runs failed (a rerun retries
    it)."""
    errors = []
    for spec in specs:
        root = root_of(out, spec)
        if results.existing(root, spec) == "failed":
            run_json = results.run_dir(root, spec) / "run.json"
            errors.append((f"runs/{root.name}/{spec.name}",
                           results.read_run_json(run_json)["error"]))
    return errors


def gather(all_universes, seeds, steps, made):
    """{universe name: its runs' records ((robot, condition, seed) -> record) when every
    one is made, else None}, from made: {spec: record}."""
    data = {}
    for u in all_universes:
        specs = [s for group in specs_of(u, seeds, steps).values() for s in group]
        data[u.name] = ({(s.label, s.condition, s.seed): made[s] for s in specs}
                        if all(s in made for s in specs) else None)
    return data
