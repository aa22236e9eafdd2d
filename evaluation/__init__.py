"""Offline experiments that join the simulator (drivers/sim) and the estimator (controller):
simulated calibration datasets, the speed-accuracy chart and the stability sweeps. The
controller never imports this package."""
