"""The paper's intrinsic behaviours as genome files (ebrl.behaviour): package data, so an
installed copy finds them by name as a clone does (`ebrl run --behaviour paper_eq8`)."""
