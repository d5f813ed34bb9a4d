"""One module per `ebrl` command (listed by experiments.cli), each holding its add_parser
(its arguments) and its run (its checks, made before any work, then its action).
arguments holds the argument types and options several commands share; common the exit
codes, the checks and the last lines they share."""
