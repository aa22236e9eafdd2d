"""The product's command, ``tactile`` (controller/cli/command.py), and the tools it runs on
the robot: one subcommand per job, each imported only when chosen."""
