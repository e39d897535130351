"""``slosh campaign``: fit (and diagnose) a whole test campaign in parallel, resumably, and
report the parameters against fill beside the tank prediction."""

from __future__ import annotations

import argparse
import sys

from analogs.errors import InputError

from ._cases import add_strict

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "campaign", help="fit and diagnose a whole test campaign, in parallel and resumable",
        description="Fit every case of a folder or glob (and diagnose it with --diagnose), then "
                    "each group of records of the same tank, fill and liquid (or the groups of "
                    "campaign.toml) in one multi-case fit without the records that disagree with "
                    "it. Each result is stored under a key of its inputs in OUT_DIR/store: a "
                    "rerun computes only what changed or is missing. Writes OUT_DIR/campaign.csv, "
                    "OUT_DIR/campaign.parquet and OUT_DIR/report/.")
    p.add_argument("source", metavar="DIR_OR_GLOB",
                   help="folder of case files (with an optional campaign.toml) or a glob of them")
    p.add_argument("--diagnose", action="store_true",
                   help="also diagnose every record (slow: about a dozen fits each)")
    p.add_argument("--out", metavar="OUT_DIR", default="campaign",
                   help="output folder (default ./campaign); rerunning into it resumes")
    p.add_argument("--model", default=None,
                   help="model specification for every fit, over campaign.toml's (default "
                        "there, else fixed,p1)")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--scheduler", metavar="ADDRESS", default=None,
                       help="run on the Dask cluster of this scheduler, e.g. tcp://host:8786")
    where.add_argument("--cluster", metavar="N", type=int, default=None,
                       help="run on an embedded Dask LocalCluster of N worker processes")
    where.add_argument("--threads", metavar="N", type=int, default=None,
                       help="threads of the local executor (default: the CPU count)")
    p.add_argument("--overwrite", action="store_true",
                   help="compute every result again instead of taking it from the store, and "
                        "write into an output folder that belongs to another campaign")
    add_strict(p)
    p.set_defaults(run=run)


def _executor(args: argparse.Namespace):
    from ..executor import DaskExecutor, LocalExecutor

    for flag, value in (("--cluster", args.cluster), ("--threads", args.threads)):
        if value is not None and value < 1:
            raise InputError(f"{flag} must be at least 1, got {value}")
    if args.scheduler is not None or args.cluster is not None:
        return DaskExecutor(args.scheduler, n_workers=args.cluster)
    return LocalExecutor(args.threads)


def run(args: argparse.Namespace) -> int:
    from ..campaign import claim_folder, discover, run_campaign, write_outputs
    from ..campaign.table import CampaignTable

    campaign = discover(args.source, model=args.model)
    CampaignTable((), (), {}).to_parquet()      # a missing pyarrow is said before any fit
    resumed = claim_folder(args.out, args.source, overwrite=args.overwrite)
    n, g = len(campaign.records), len(campaign.groups)
    print(f"campaign {campaign.source}: {n} record{'s' * (n != 1)} in {g} group{'s' * (g != 1)}"
          + (", resuming" if resumed else ""))
    try:
        with _executor(args) as executor:
            result = run_campaign(campaign, args.out, executor=executor, diagnose=args.diagnose,
                                  recompute=args.overwrite, strict=args.strict)
    except KeyboardInterrupt:
        print(f"\ninterrupted: finished results are kept in {args.out}/store; run the same "
              "command again to resume", file=sys.stderr)
        return 130
    table = write_outputs(result, args.out)
    failed = [r["id"] for r in table.rows if r["status"] == "failed"]
    print(f"{result.computed} tasks computed, {result.reused} taken from the store in "
          f"{result.seconds:.1f} s; {len(failed)} failed" + (f": {', '.join(failed)}" if failed
                                                              else ""))
    for o in result.outliers:
        print(f"outlier {o.record} (group {o.group}): {o.reasons[0]}")
    print(f"wrote {args.out}/campaign.csv, {args.out}/campaign.parquet, {args.out}/report/")
    return 1 if failed else 0
