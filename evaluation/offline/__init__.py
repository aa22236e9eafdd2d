"""The user's offline tools on tactile data, recorded or simulated: estimate (estimate_cli),
calibrate (calibrate_cli), make a simulated dataset (make_dataset_cli, jig_dataset), the
dataset format and its fit (dataset, dataset_fit), and the estimator demo (estimator_demo)."""
