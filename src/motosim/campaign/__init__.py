"""Campaigns: thousands of runs of one designed stack over varied plants, sensors and riders.

A campaign file (:mod:`motosim.campaign.spec`) names a base scenario and the factors to vary;
:func:`plan_campaign` draws the runs, :func:`run_campaign` designs once per distinct design
and runs the rest in batches on joblib or Dask, writing Parquet parts and a manifest
(:mod:`motosim.campaign.results`) and optionally each run's time series in Zarr
(:mod:`motosim.campaign.series`); :func:`rerun` reproduces one run exactly.
"""

from motosim.campaign.execute import CampaignSummary, rerun, rerun_series, run_campaign
from motosim.campaign.plan import Plan, PlannedRun, plan_campaign
from motosim.campaign.results import load_results, read_manifest
from motosim.campaign.series import load_series
from motosim.campaign.spec import METRICS, Campaign, Factor, load_campaign, parse_campaign

__all__ = [
    "METRICS",
    "Campaign",
    "CampaignSummary",
    "Factor",
    "Plan",
    "PlannedRun",
    "load_campaign",
    "load_results",
    "load_series",
    "parse_campaign",
    "plan_campaign",
    "read_manifest",
    "rerun",
    "rerun_series",
    "run_campaign",
]
