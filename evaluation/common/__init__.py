"""What the evaluation's tools and experiments share: command-line support (cli_support),
output paths and atomic writes (outputs), the machine line of a report (machine_info), and
the simulator's pieces (sim_setup) and camera renderer (rendering) set up by name."""
