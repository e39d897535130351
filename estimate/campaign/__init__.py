"""Test campaigns: fit (and diagnose) every record of a tank test program in parallel,
resumably, fit each group of records that share a tank and fill together, flag the records
that disagree with their group, and report the parameters against fill beside the tank
module's prediction.

* :mod:`~estimate.campaign.discovery` - the records and groups of a folder or glob;
* :mod:`~estimate.campaign.store` - results stored under a key of their inputs;
* :mod:`~estimate.campaign.tasks` - one fit or diagnosis, on any worker;
* :mod:`~estimate.campaign.runner` - the stages on an executor (:mod:`estimate.executor`);
* :mod:`~estimate.campaign.outliers` - records against their group;
* :mod:`~estimate.campaign.table`, :mod:`~estimate.campaign.report`,
  :mod:`~estimate.campaign.plots`, :mod:`~estimate.campaign.predictions` - the outputs.

Examples
--------
>>> from estimate.campaign import discover, run_campaign, write_outputs
>>> run = run_campaign(discover("examples/campaign"), "campaign")     # doctest: +SKIP
>>> table = write_outputs(run, "campaign")                             # doctest: +SKIP
"""

from .discovery import Campaign, Group, Record, Setup, discover
from .outliers import Outlier, find_outliers
from .report import claim_folder, write_outputs
from .runner import CampaignRun, run_campaign
from .store import Store, task_key
from .table import CampaignTable, campaign_table

__all__ = [
    "Campaign",
    "CampaignRun",
    "CampaignTable",
    "Group",
    "Outlier",
    "Record",
    "Setup",
    "Store",
    "campaign_table",
    "claim_folder",
    "discover",
    "find_outliers",
    "run_campaign",
    "task_key",
    "write_outputs",
]
