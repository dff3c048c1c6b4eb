"""Statistical campaigns: many lockstep runs of one scenario, dispersed, on Dask.

- :mod:`~bench.campaign.spec`: the campaign file (study, seed, dispersions), validated;
- :mod:`~bench.campaign.distributions`: uniform, truncated normal, choice, sweep;
- :mod:`~bench.campaign.paths`: scenario keys with element indices;
- :mod:`~bench.campaign.cases`: the cases (``--set`` overrides + run seed), pure;
- :mod:`~bench.campaign.case_run`: one case as one ``thruster-hil run`` process;
- :mod:`~bench.campaign.engine`: the cases on a local Dask cluster or a scheduler;
- :mod:`~bench.campaign.stats`: pass rates (Wilson), percentiles, worst, sensitivity;
- :mod:`~bench.campaign.report`: campaign.csv/.json/.html;
- :mod:`~bench.campaign.margin`: a requirement's margin on one key, by bisection;
- :mod:`~bench.campaign.cli`, :mod:`~bench.campaign.tools`: the commands.
"""
