"""The check of a behaviour file given on the command line (`ebrl run --behaviour FILE`,
`ebrl evolve --start FILE`), made before any work: the genome, or one line that says why
it does not fit the robots. It reads the robots' composed models, so it imports the
simulator: the commands import it once they are past their light checks
(experiments.checks.validate)."""
from ebrl import behaviour as genomes
from tasks import beams, compiled_model
from tasks.robots import resolve


def range_beams(entry):
    """The number of a robot's beams: its composed model's rangefinders, which its
    observation's `range` holds (no task loaded)."""
    model, _ = compiled_model(entry, entry.task_config())
    return len(beams.beam_sensors(model))


def check(path, robots, drive=None, overrides=()):
    """`--behaviour FILE` for these robots: the genome, or ValueError (one line) when the
    file is bad, its behaviour is not the robots' (eq8 for the two-wheel drive, eq9-10
    for the floating one), its weights do not match a robot's beams, or a --set names a
    field the genome sets."""
    genome = genomes.load(path)
    for robot in robots:
        entry = resolve(robot, drive)
        if entry.avoidance != genome.behaviour:
            raise ValueError(f"behaviour file {path}: a {genome.behaviour} genome, but "
                             f"{entry.name} uses {entry.avoidance}")
        count = range_beams(entry)
        if genome.beams() != count:
            raise ValueError(f"behaviour file {path}: {genome.beams()} weights, but "
                             f"{entry.name} has {count} beams")
    genome_sets = set(genomes.CONFIG_FIELDS.values()) | {"eq9_dead_zone"}
    clash = sorted(k for k, _ in overrides if k in genome_sets)
    if clash:
        raise ValueError(f"--set {clash[0]} conflicts with --behaviour, which sets it; "
                         "change the file instead")
    return genome
