"""What the evaluation's tools and experiments share: the machine line of a report
(machine_info), and the simulator's pieces (sim_setup) and camera renderer (rendering) set up
by name. Their command-line support and output files are the product's (controller/cli/)."""
