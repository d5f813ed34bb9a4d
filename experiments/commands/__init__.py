"""One module per `ebrl` command (listed by experiments.cli)."""
