"""`ebrl evolve`: CMA-ES over a robot's intrinsic behaviour (ebrl.behaviour), Section 4's
proposal, through the study runner of `ebrl fit` (experiments.studies.study): the same storage,
batches, resume and runs on disk; only the space and the objective differ.

The space (Problem.distributions): every number of the starting genome (the paper's rule
for the robot's drive, or --start FILE) in the chosen fields, each within its field's
radius (RADII) of its start and clipped to a valid genome (DOMAIN). Optuna's CmaEsSampler
starts at the middle of the bounds, the starting genome, with its default step, a sixth
of each range. Trial 0 is the starting genome itself, alone (its fitness is the baseline, and
CMA-ES needs one complete trial to know the space); then each batch of --population
trials is one CMA-ES generation.

The fitness (Problem.score): the mean over the training seeds of the goals reached within
the budget, EBRL learning from step 0 in the avoidance condition as in the protocol
(experiments.running.execution.execute); the study minimises its negative. Why goals rather than
steps per trial: goals are defined for every run, also one that never reaches the goal
(steps per trial would have to drop such a seed, rewarding a behaviour that fails on it,
or invent a penalty); they are the return the learner maximises (the cumulative reward
at the budget); and at a fixed budget more goals is fewer steps per trial, the figure
the comparison reports. Steps per trial and first trials are recorded beside them.

--no-learning evolves the behaviour as a controller: exploration_rate=1 (an existing
ebrl.Config field), so the agent's exploration draw sends every step to the fallback and
the memory never acts; the learning variables' initial values then do nothing and leave
the space.
"""
import dataclasses
import json
import math
import pathlib

from ebrl import behaviour as genomes
from experiments.checks import behaviour_file
from experiments.outputs import plots, report
from experiments.running import results
from experiments.running import runner
from experiments.running.execution import RunSpec
from experiments.studies import study
from tasks.robots import ROBOTS

#: The search's radius of each field (of a vector's every entry) around the starting
#: genome: each number is searched in [start - radius, start + radius], so CMA-ES's mean
#: starts at the starting genome (the middle of its bounds) with its default step, a
#: sixth of each range (a third of the radius). Weights and biases are on the readings'
#: scale (eq 8's largest weight is 0.5, eq 10's 0.5).
RADII = {
    "weights": 0.75, "weights_h": 0.75, "weights_v": 0.75, "bias": 0.5, "gain": 1.0,
    "threshold": 0.25, "hold": 0.5, "random_rate": 0.2, "random_sd": 0.45,
    "initial_reliability": 0.5, "initial_utility": 0.5,
}
#: Where a searched number is clipped to a valid genome (ebrl.behaviour's checks).
DOMAIN = {"random_rate": (0.0, 1.0), "hold": (0.0, 1.0), "initial_reliability": (0.0, 1.0),
          "random_sd": (0.01, math.inf), "threshold": (0.0, 0.95), "gain": (0.0, math.inf)}
LEARNING_FIELDS = ("initial_reliability", "initial_utility")
#: --no-learning: the memory never acts (every step explores, so the fallback acts).
NO_LEARNING = (("exploration_rate", 1.0),)
CONDITION = "avoidance"


def study_name(robot_label, learning=True):
    return f"evolve-{robot_label}" + ("" if learning else "-controller")


def fields(genome, chosen="all", learning=True):
    """The genome fields a search changes: `chosen` (comma-separated, or "all"), less the
    learning variables without learning and weights_v when the genome has none (eq 10's
    symmetry). ValueError (one line) for a field the genome does not have."""
    have = [f.name for f in dataclasses.fields(genome)]
    if chosen == "all":
        names = [n for n in have if learning or n not in LEARNING_FIELDS]
    else:
        names = [n.strip() for n in chosen.split(",") if n.strip()]
        unknown = next((n for n in names if n not in have), None)
        if unknown is not None or not names:
            raise ValueError(f"unknown field {unknown or chosen!r} in --space for "
                             f"{genome.behaviour}; valid: {', '.join(have)}")
        from experiments.checks.validate import once
        once(names, "--space")
        if not learning and any(n in LEARNING_FIELDS for n in names):
            raise ValueError("--space names a learning variable, which --no-learning leaves "
                             "unused: " + ", ".join(n for n in names if n in LEARNING_FIELDS))
        if "weights_v" in names and genome.weights_v is None:
            raise ValueError("--space weights_v needs a --start genome whose weights_v is a "
                             "list (null is eq 10's symmetry: b_h's weights turned)")
    return tuple(n for n in names if getattr(genome, n) is not None)


def paper_genome(entry):
    """The paper's rule for a robot's drive as a genome, with the robot's readings of the
    learning variables and the dead zone (its agent config, execution.RunSpec)."""
    drive = None if entry.name in ROBOTS else entry.drive  # a robot file: its drive
    config = RunSpec(entry.name, CONDITION, 0, 1, drive=drive).agent_config()
    return genomes.paper(entry.avoidance, behaviour_file.range_beams(entry), config)


#: The paper's robots whose rules ship as behaviours/paper_<behaviour>.json.
PAPER_FILE_ROBOTS = ("two_wheel", "floating")


def write_paper(folder):
    """The paper's rules, with the paper's robots' readings, as behaviour files,
    FOLDER/paper_<behaviour>.json (the shipped behaviours/ folder is made so:
    `python -c 'from experiments.studies import evolve; evolve.write_paper("behaviours")'`;
    tests/test_evolve.py checks it is current)."""
    folder = pathlib.Path(folder)
    entries = [ROBOTS[r] for r in PAPER_FILE_ROBOTS]
    return [genomes.save(paper_genome(e), folder / f"paper_{e.avoidance}.json")
            for e in entries]


@dataclasses.dataclass
class Problem:
    """`ebrl evolve` for experiments.studies.study: the space, a trial's runs, its fitness."""
    robot: str
    start: object                  # the starting genome (ebrl.behaviour)
    names: tuple                   # the genome fields searched
    seeds: tuple
    steps: int = None              # None: the robot's budget
    learning: bool = True
    population: int = 8
    sampler_seed: int = 0
    drive: str = None
    room: str = None               # models.rooms' room; None: the paper's

    @property
    def rungs(self):
        return (tuple(self.seeds),)

    def x0(self):
        return genomes.flat(self.start, self.names)

    def distributions(self):
        import optuna
        out = {}
        for k, v in self.x0().items():
            r = RADII[k.partition(".")[0]]
            out[k] = optuna.distributions.FloatDistribution(v - r, v + r)
        return out

    def genome(self, params):
        """The genome of a trial's numbers, each clipped to its DOMAIN."""
        clipped = {}
        for k, v in params.items():
            lo, hi = DOMAIN.get(k.partition(".")[0], (-math.inf, math.inf))
            clipped[k] = min(max(v, lo), hi)
        return genomes.with_flat(self.start, clipped)

    def specs(self, params, seeds):
        genome = self.genome(params)
        overrides = () if self.learning else NO_LEARNING
        return [dataclasses.replace(s, behaviour=genome) for s in
                runner.plan((self.robot,), (CONDITION,), seeds, self.steps, overrides,
                            self.drive, room=self.room)]

    def score(self, params, runs):
        ms = [runs[k]["metrics"] for k in sorted(runs)]
        goals = [m["goals"] for m in ms]
        per_trial = [m["steps_per_trial"] for m in ms if m["steps_per_trial"] is not None]
        first = [m["first_trial_steps"] for m in ms if m["first_trial_steps"] is not None]
        mean = lambda v: sum(v) / len(v) if v else None  # noqa: E731
        value = -mean(goals)
        return value, {"goals": mean(goals), "goals_by_seed": goals,
                       "steps_per_trial": mean(per_trial), "first_trial_steps": mean(first),
                       "reached": len(first)}

    def settings(self):
        """What a study's trials depend on; a resumed study must have the same."""
        return {"robot": self.robot, "drive": self.drive, "start": genomes.to_dict(self.start),
                "space": list(self.names), "seeds": list(self.seeds), "steps": self.steps,
                "learning": self.learning, "population": self.population,
                "sampler_seed": self.sampler_seed} | ({} if self.room is None else {"room": self.room})

    def sampler(self, n_trials):
        """CMA-ES for the batch starting at trial n_trials, seeded from the sampler seed
        and n_trials (so a resumed study samples as an unbroken one)."""
        import warnings

        import optuna
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
            return optuna.samplers.CmaEsSampler(
                seed=(self.sampler_seed * 1_000_003 + n_trials) % 2**31,
                popsize=self.population, n_startup_trials=1,
                warn_independent_sampling=False)


def check_settings(s, problem):
    """Records the problem's settings in a new study; ValueError (one line) when a study
    holding trials was made with other settings."""
    want = json.loads(json.dumps(problem.settings()))
    have = s.user_attrs.get("settings")
    if have is None:
        s.set_user_attr("settings", want)
        return
    diff = next((k for k in want if have.get(k) != want[k]), None)
    if diff is not None:
        raise ValueError(f"study {s.study_name} was made with other settings ({diff}: "
                         f"{have.get(diff)!r}, now {want[diff]!r}); use another --study or --out")


def generation(trial):
    """A trial's CMA-ES generation (1 = the first), 0 for the starting genome."""
    g = trial.system_attrs.get("cma:generation")
    return 0 if g is None else g + 1


def complete(s):
    import optuna
    return [t for t in s.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,))
            if "rungs" in t.user_attrs]


def fitness_rows(s):
    """(generation, trials, best goals, mean goals, best so far) per generation."""
    by_gen = {}
    for t in complete(s):
        by_gen.setdefault(generation(t), []).append(study.deepest(t)["goals"])
    rows, best = [], -math.inf
    for g in sorted(by_gen):
        v = by_gen[g]
        best = max(best, max(v))
        rows.append((g, len(v), max(v), sum(v) / len(v), best))
    return rows


def fitness_figure(s, path):
    plt = plots.pyplot()
    done = complete(s)
    fig, ax = plt.subplots(figsize=(7, 3.5))
    ax.scatter([generation(t) for t in done], [study.deepest(t)["goals"] for t in done],
               s=12, alpha=0.6, label="trial")
    rows = fitness_rows(s)
    ax.step([r[0] for r in rows], [r[4] for r in rows], where="post", color="C3",
            label="best so far")
    ax.set_xlabel("generation (0: the starting genome)")
    ax.set_ylabel("mean goals over the training seeds")
    ax.legend(loc="lower right", fontsize=8)
    return plots.save(fig, path, dpi=110)


def best_genome(s, problem):
    """(trial, genome) of the complete trial with the most goals (the first such)."""
    best = study.best_trials(s, 1)
    if not best:
        return None, None
    return best[0], problem.genome({k: v for k, v in best[0].params.items()})


def write(s, out, problem):
    """OUT/<study>_best.json (the best genome), OUT/<study>.md and OUT/<study>_fitness.png;
    returns the .md's path (a storage that fails meanwhile: study.StorageError)."""
    with study.storage_errors(s):
        return _write(s, out, problem)


def _write(s, out, problem):
    out = pathlib.Path(out)
    name = s.study_name
    trial, genome = best_genome(s, problem)
    lines = [f"# `ebrl evolve`: study `{name}`", "",
             f"Robot {problem.robot}, "
             f"{'EBRL learning' if problem.learning else 'no learning (the behaviour alone)'}"
             f", seeds {', '.join(map(str, problem.seeds))}, "
             f"{problem.steps or 'the robot budget'} steps a run, population {problem.population}. "
             "Fitness: mean goals within the budget over those seeds (experiments/studies/evolve.py).", "",
             "| generation | trials | best goals | mean goals | best so far |",
             "|---:|---:|---:|---:|---:|"]
    for g, n, b, m, so_far in fitness_rows(s):
        lines.append(f"| {g} | {n} | {b:.2f} | {m:.2f} | {so_far:.2f} |")
    if genome is not None:
        results.atomic_write(out / f"{name}_best.json", genomes.dumps(genome))
        d = study.deepest(trial)
        start = genomes.to_dict(problem.start)
        lines += ["", f"Best: trial {trial.number} (generation {generation(trial)}), "
                  f"{d['goals']:.2f} goals, steps per trial "
                  f"{report.fmt(d['steps_per_trial'])}; saved as `{name}_best.json`.", "",
                  "| field | start | best |", "|---|---|---|"]
        for k, v in genomes.to_dict(genome).items():
            lines.append(f"| {k} | {_show(start[k])} | {_show(v)} |")
    if complete(s):
        fitness_figure(s, out / f"{name}_fitness.png")
        lines += ["", f"![fitness over generations]({name}_fitness.png)", ""]
    path = out / f"{name}.md"
    results.atomic_write(path, "\n".join(lines) + "\n")
    return path


def _show(v):
    if isinstance(v, list):
        return "[" + ", ".join(f"{x:.3g}" for x in v) + "]"
    return f"{v:.3g}" if isinstance(v, float) else json.dumps(v)
