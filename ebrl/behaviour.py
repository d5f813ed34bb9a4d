"""A parametric family of intrinsic behaviours that holds Section 3.4's rules as one point.

Section 4 proposes to evolve the intrinsic strategy and the learning variables' initial
values. A genome here is a plain record (a frozen dataclass, saved as JSON) of one of two
families, named by the behaviour it generalises (ebrl.intrinsic.BEHAVIOURS):

Turning ("eq8"), for n beams s_1..s_n (leftmost first, scaled to [0, 1])::

    a = clip(gain * (sum_i weights[i] * s_i + bias), -1, 1)       a > 0 turns right

eq 8 is weights[i] = i / sum_{j<=n//2} j on the left half (i = 1..n//2), the negative
mirror on the right half (weights[n+1-i] = -weights[i]), 0 for a middle beam, bias 0,
gain 1 (eq 8 never leaves [-1, 1], so its clip does nothing).

Accelerating ("eq9-10"), for the beams E, NE, N, NW, W, SW, S, SE::

    b_h = sum_k weights_h[k] * s_k + bias[0]
    b_v = sum_k weights_v[k] * s_k + bias[1]     weights_v None: weights_h turned by 90 degrees
    a   = clip(gain * (b - threshold) / (1 - threshold), -1, 1)   if b >= threshold
          clip(gain * (b + threshold) / (1 - threshold), -1, 1)   if b <= -threshold
          hold * (the fallback's previous acceleration on that axis)   otherwise

eq 9-10 is weights_h = (-0.5, -0.25, 0, 0.25, 0.5, 0.25, 0, -0.25) (eq 10's 0.5 (s_W -
s_E) + 0.25 (s_NW + s_SW - s_NE - s_SE)), weights_v None (the paper's "symmetrical
equation": weights_v[k] = weights_h[k - 2], so b_v = 0.5 (s_S - s_N) + ...), bias 0,
threshold 0.25, gain 1; hold is eq 9's "not changed": 0 for the eq9_dead_zone reading
"zero", 1 for "keep" (ebrl.config.READINGS), and anything between keeps that share.

Both families also hold the fallback's random share (random_rate, Section 3.4's 20%) and
spread (random_sd, its 0.5), and the learning variables' initial values
(initial_reliability, initial_utility: a new memory element's, ebrl.Config's fields).

A genome whose shape-giving fields are exactly the paper's (is_paper_rule()) acts through
ebrl.intrinsic's own functions, so that its runs are bit-identical to the default's;
any other point is evaluated by the formulas above (which agree with eq 8 and eq 9-10
to the last bits or so at the paper's point: tests/test_evolve.py).
"""
import dataclasses
import json
import sys
import math
import pathlib

import numpy as np

from ebrl import intrinsic
from ebrl.config import CONDITIONS, Config, READINGS

#: The beams of eq 10, counter-clockwise from East (the floating robot's order).
EQ10_BEAMS = ("E", "NE", "N", "NW", "W", "SW", "S", "SE")
#: eq 10's weights of b_h on those beams.
EQ10_WEIGHTS = (-0.5, -0.25, 0.0, 0.25, 0.5, 0.25, 0.0, -0.25)
#: The behaviours a genome generalises (ebrl.intrinsic.BEHAVIOURS' keys).
FAMILIES = ("eq8", "eq9-10")


class GenomeError(ValueError):
    """A genome that cannot be used; the message is one line naming the field."""


def _turned(weights):
    """b_h's weights turned by 90 degrees counter-clockwise: b_v's (eq 10's symmetry)."""
    return tuple(weights[(k - 2) % 8] for k in range(8))


def _clip1(x):
    return -1.0 if x < -1.0 else (1.0 if x > 1.0 else x)


@dataclasses.dataclass(frozen=True)
class Turning:
    """eq 8's family (module docstring). Each field moves the behaviour so:

    weights: one per beam, leftmost first; a beam with a positive weight turns the robot
        right (away from the left) in proportion to its reading; 0 ignores it.
    bias: the turn with nothing in view (> 0: right); a constant curve.
    gain: scales the whole turn; past |a| = 1 the turn saturates.
    random_rate: the share of fallback steps that take the random action instead.
    random_sd: the random action's spread (Gaussian, mean 0, clipped to [-1, 1]).
    initial_reliability, initial_utility: a new memory element's values (ebrl.Config).
    """
    weights: tuple
    bias: float
    gain: float
    random_rate: float
    random_sd: float
    initial_reliability: float
    initial_utility: float
    behaviour = "eq8"

    def __post_init__(self):
        object.__setattr__(self, "_w", np.asarray(self.weights, dtype=np.float64))

    def avoid(self, ranges):
        """The turn for ranges (scaled to [0, 1], leftmost first)."""
        return _clip1(self.gain * (float(np.dot(self._w, ranges)) + self.bias))

    def shape_fields(self):
        return ("weights", "bias", "gain")

    def beams(self):
        return len(self.weights)


@dataclasses.dataclass(frozen=True)
class Accelerating:
    """eq 9-10's family (module docstring). Each field moves the behaviour so:

    weights_h: b_h's weight on each beam E, NE, N, NW, W, SW, S, SE; a positive weight
        accelerates East (+h) when that beam sees something.
    weights_v: b_v's weights on the same beams (+v is North); None: weights_h turned by
        90 degrees (eq 10's symmetrical equation).
    bias: (h, v) added to b_h and b_v: a drift with nothing in view.
    threshold: eq 9's theta; |b| below it is the dead zone (no new acceleration).
    gain: scales eq 9's ramp (b - theta) / (1 - theta); past 1 it saturates.
    hold: in the dead zone, the share of the fallback's previous acceleration kept
        (0: none, eq9_dead_zone "zero"; 1: all of it, "keep").
    random_rate, random_sd, initial_reliability, initial_utility: as in Turning.
    """
    weights_h: tuple
    weights_v: tuple
    bias: tuple
    threshold: float
    gain: float
    hold: float
    random_rate: float
    random_sd: float
    initial_reliability: float
    initial_utility: float
    behaviour = "eq9-10"

    def __post_init__(self):
        wv = _turned(self.weights_h) if self.weights_v is None else self.weights_v
        object.__setattr__(self, "_w", np.array([self.weights_h, wv], dtype=np.float64))
        object.__setattr__(self, "_k", self.gain / (1.0 - self.threshold))

    def avoid(self, ranges, previous=None):
        """(a_h, a_v) for ranges (scaled to [0, 1], E first, counter-clockwise);
        previous: the fallback's last acceleration (None: zero)."""
        b = self._w.dot(np.asarray(ranges, dtype=np.float64)).tolist()
        t, k, hold, bias = self.threshold, self._k, self.hold, self.bias
        out = [0.0, 0.0]
        for i in (0, 1):
            x = b[i] + bias[i]
            if x >= t:
                x = k * (x - t)     # gain (b - theta) / (1 - theta)
            elif x <= -t:
                x = k * (x + t)
            else:
                out[i] = 0.0 if previous is None else hold * float(previous[i])
                continue
            out[i] = -1.0 if x < -1.0 else (1.0 if x > 1.0 else x)
        return np.array(out)

    def shape_fields(self):
        return ("weights_h", "weights_v", "bias", "threshold", "gain")

    def beams(self):
        return len(self.weights_h)


CLASSES = {"eq8": Turning, "eq9-10": Accelerating}
#: The fields a genome shares with ebrl.Config, by genome field.
CONFIG_FIELDS = {"random_rate": "intrinsic_random_rate", "random_sd": "random_sd",
                 "initial_reliability": "initial_reliability",
                 "initial_utility": "initial_utility"}


def paper(behaviour, beams=None, config=None):
    """Section 3.4's rule as a genome: eq 8 for `beams` beams (7, the two-wheel robot's,
    by default) or eq 9-10, with the paper's random share and spread and the config's
    (ebrl.Config, its defaults when None) values for what the paper leaves open (the
    learning variables' initial values and, for eq 9-10, the dead zone's reading)."""
    c = Config() if config is None else config
    common = dict(random_rate=c.intrinsic_random_rate, random_sd=c.random_sd,
                  initial_reliability=float(c.initial_reliability),
                  initial_utility=float(c.initial_utility))
    if behaviour == "eq8":
        n = 7 if beams is None else int(beams)
        half = n // 2
        total = half * (half + 1) // 2
        w = [0.0] * n
        for i in range(1, half + 1):
            w[i - 1] = i / total
            w[n - i] = -i / total
        return Turning(weights=tuple(w), bias=0.0, gain=1.0, **common)
    if behaviour == "eq9-10":
        hold = 1.0 if c.eq9_dead_zone == "keep" else 0.0
        return Accelerating(weights_h=EQ10_WEIGHTS, weights_v=None, bias=(0.0, 0.0),
                            threshold=intrinsic.THETA, gain=1.0, hold=hold, **common)
    raise GenomeError(f"unknown behaviour {behaviour!r}; valid: {', '.join(FAMILIES)}")


def is_paper_rule(genome):
    """Whether the genome's shape (every field but the random action's and the learning
    variables', and hold, which ebrl.intrinsic handles at 0 and 1) is the paper's."""
    ref = paper(genome.behaviour, genome.beams())
    return all(getattr(genome, f) == getattr(ref, f) for f in genome.shape_fields())


def fallback(genome, condition, random_in_avoidance=READINGS["random_in_avoidance"][0],
             random_demand=READINGS["random_demand"][0]):
    """The fallback of Section 3.6's condition with this genome: "random", the random
    walk at the genome's spread; "avoidance", its behaviour with the random action at
    its share (ebrl.intrinsic.Intrinsic). At the paper's rule the fallback is
    ebrl.intrinsic.fallback_for's own (bit-identical runs)."""
    hold = getattr(genome, "hold", 0.0)
    if condition == "random" or (is_paper_rule(genome) and hold in (0.0, 1.0)):
        return intrinsic.fallback_for(genome.behaviour, condition, genome.random_rate,
                                      genome.random_sd,
                                      eq9_dead_zone="keep" if hold == 1.0 else "zero",
                                      random_in_avoidance=random_in_avoidance,
                                      random_demand=random_demand)
    if condition != "avoidance":
        raise ValueError(f"unknown condition {condition!r}; valid: "
                         f"{', '.join(CONDITIONS)}")
    dim = intrinsic.BEHAVIOURS[genome.behaviour][1]
    return intrinsic.Intrinsic(genome.avoid, dim, genome.random_rate, genome.random_sd,
                               random_in_avoidance=random_in_avoidance, hold=hold != 0.0,
                               uniform=random_demand == "uniform_all")


def config_fields(genome):
    """{ebrl.Config field: value} that the genome sets (its random action and the
    learning variables' initial values)."""
    return {CONFIG_FIELDS[k]: getattr(genome, k) for k in CONFIG_FIELDS}


# -- JSON ---------------------------------------------------------------------------
def to_dict(genome):
    """The genome as plain JSON data, its behaviour first."""
    out = {"behaviour": genome.behaviour}
    for f in dataclasses.fields(genome):
        v = getattr(genome, f.name)
        out[f.name] = list(v) if isinstance(v, tuple) else v
    return out


def dumps(genome):
    """The genome's JSON text: one field a line, vectors on their line."""
    items = [f"  {json.dumps(k)}: {json.dumps(v)}" for k, v in to_dict(genome).items()]
    return "{\n" + ",\n".join(items) + "\n}\n"


#: Each scalar field's allowed range (inclusive unless noted) and what it is.
_RANGES = {
    "random_rate": (0.0, 1.0), "initial_reliability": (0.0, 1.0), "hold": (0.0, 1.0),
}


def _number(name, v):
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise GenomeError(f"field {name}: not a number ({v!r})")
    try:
        v = float(v)
    except OverflowError:  # an integer past the largest float
        raise GenomeError(f"field {name}: not a finite number (an integer of "
                          f"{len(str(abs(v)))} digits)") from None
    if not math.isfinite(v):
        raise GenomeError(f"field {name}: not a finite number ({v!r})")
    return v


def _vector(name, v, length=None):
    if not isinstance(v, (list, tuple)):
        raise GenomeError(f"field {name}: not a list of numbers ({v!r})")
    if length is not None and len(v) != length:
        raise GenomeError(f"field {name}: {len(v)} values, need {length}")
    return tuple(_number(f"{name}[{i}]", x) for i, x in enumerate(v))


def from_dict(data):
    """A genome from JSON data; GenomeError (one line naming the field) when a field is
    missing, unknown, of the wrong length or not a finite number in its range."""
    if not isinstance(data, dict):
        raise GenomeError("not a JSON object")
    behaviour = data.get("behaviour")
    if not isinstance(behaviour, str) or behaviour not in CLASSES:
        raise GenomeError(f"field behaviour: {behaviour!r}; valid: {', '.join(FAMILIES)}")
    cls = CLASSES[behaviour]
    names = [f.name for f in dataclasses.fields(cls)]
    unknown = [k for k in data if k not in names and k != "behaviour"]
    if unknown:
        raise GenomeError(f"unknown field {unknown[0]!r} for {behaviour}; fields: "
                          + ", ".join(names))
    missing = [k for k in names if k not in data]
    if missing:
        raise GenomeError(f"missing field {missing[0]!r} for {behaviour}")
    values = {}
    for name in names:
        v = data[name]
        if name == "weights":
            values[name] = _vector(name, v)
            if len(values[name]) < 2:
                raise GenomeError(f"field weights: {len(values[name])} values, need one per beam")
        elif name == "weights_h":
            values[name] = _vector(name, v, 8)
        elif name == "weights_v":
            values[name] = None if v is None else _vector(name, v, 8)
        elif name == "bias" and behaviour == "eq9-10":
            values[name] = _vector(name, v, 2)
        else:
            values[name] = _number(name, v)
    for name, (lo, hi) in _RANGES.items():
        if name in values and not lo <= values[name] <= hi:
            raise GenomeError(f"field {name}: {values[name]:g} is outside [{lo:g}, {hi:g}]")
    if values["random_sd"] <= 0:
        raise GenomeError(f"field random_sd: must be positive, got {values['random_sd']}")
    if "threshold" in values and not 0.0 <= values["threshold"] < 1.0:
        raise GenomeError(f"field threshold: {values['threshold']} is outside [0, 1)")
    return cls(**values)


def shipped(path):
    """A shipped behaviour file (the `behaviours` package's data: paper_eq8.json,
    paper_eq9-10.json) named by its file name, its stem or behaviours/<name>, where no
    file lies at `path` itself: found in an installed copy as in a clone."""
    path = pathlib.Path(path)
    if path.is_file() or path.is_absolute() or (len(path.parts) > 1 and path.parts[0] != "behaviours"):
        return path
    import importlib.resources
    try:
        folder = importlib.resources.files("behaviours")
    except ModuleNotFoundError:
        return path
    name = path.name if path.suffix == ".json" else path.name + ".json"
    found = folder / name
    return pathlib.Path(str(found)) if found.is_file() else path


def load(path):
    """The genome in a JSON file (or a shipped one by name, `shipped`); GenomeError (one
    line, naming the file) otherwise."""
    path = shipped(path)
    try:
        data = json.loads(path.read_bytes().decode("utf-8"))
    except OSError as e:
        raise GenomeError(f"behaviour file {path}: {e.strerror or e}") from None
    except UnicodeDecodeError:
        raise GenomeError(f"behaviour file {path}: not JSON (not UTF-8 text)") from None
    except RecursionError:
        raise GenomeError(f"behaviour file {path}: not JSON (nested too deeply)") from None
    except ValueError as e:  # JSONDecodeError; an integer past Python's 4300 digits
        said = str(e).splitlines()[0][:100] if str(e) else type(e).__name__
        if "Exceeds the limit" in said:
            said = f"an integer of more than {sys.get_int_max_str_digits()} digits"
        raise GenomeError(f"behaviour file {path}: not JSON ({said})") from None
    try:
        return from_dict(data)
    except GenomeError as e:
        raise GenomeError(f"behaviour file {path}: {e}") from None


def save(genome, path):
    pathlib.Path(path).write_text(dumps(genome))
    return path


# -- a flat vector, for a search ------------------------------------------------------
def flat(genome, fields=None):
    """{name: value} of the genome's numbers, vectors as name.0, name.1, ...; only the
    given fields (default: all; weights_v when it is a list)."""
    out = {}
    for f in dataclasses.fields(genome):
        if fields is not None and f.name not in fields:
            continue
        v = getattr(genome, f.name)
        if v is None:
            continue
        if isinstance(v, tuple):
            out.update({f"{f.name}.{i}": float(x) for i, x in enumerate(v)})
        else:
            out[f.name] = float(v)
    return out


def with_flat(genome, values):
    """The genome with the flat values (from flat's names) replaced."""
    changes = {}
    for key, v in values.items():
        name, _, index = key.partition(".")
        if index:
            current = list(changes.get(name, getattr(genome, name)))
            current[int(index)] = float(v)
            changes[name] = tuple(current)
        else:
            changes[name] = float(v)
    return dataclasses.replace(genome, **changes)


