"""``interlock sweep``: a design space swept point by point, records as they arrive."""

from __future__ import annotations

import argparse
import sys
import warnings

from interlock.cli.common import whole_number


def add_parser(commands) -> None:
    sweep = commands.add_parser(
        "sweep", help="sweep a design space (deformations or tilings) and record the verdicts at every point",
        description="Evaluate a TOML sweep spec (see interlock.sweep.spec) point by point, on local processes "
                    "or a Dask cluster; records go to JSON lines or Parquet as they arrive, so a stopped sweep "
                    "resumes. A sweep over two parameters also gets a PNG map per verdict (with the plot extra).",
        epilog="examples:\n  interlock sweep p1.toml -o p1.jsonl\n  interlock sweep p1.toml -o p1.jsonl --resume\n"
               "  interlock sweep p1.toml -o p1.parquet --scheduler tcp://10.0.0.5:8786",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sweep.add_argument("spec", help="the sweep spec (TOML)")
    sweep.add_argument("-o", "--output", required=True, metavar="RESULTS",
                       help="*.jsonl or *.parquet, in a folder that exists")
    sweep.add_argument("--scheduler", metavar="ADDRESS",
                       help="a running Dask scheduler, e.g. tcp://10.0.0.5:8786 (needs the sweep extra)")
    sweep.add_argument("--workers", type=whole_number, metavar="N", help="local processes (default: all cores)")
    sweep.add_argument("--resume", action="store_true",
                       help="keep the records in RESULTS (they must be of this spec), evaluate the rest")
    sweep.add_argument("--max-points", type=whole_number, default=None, metavar="N",
                       help="refuse a spec with more points than N (default 1,000,000)")
    sweep.set_defaults(run=run)


def run(args) -> int:
    from collections import Counter
    from pathlib import Path

    from tqdm import tqdm

    from interlock.sweep import MAX_POINTS, SweepError, SweepWarning, check_size, load_spec, run

    spec = load_spec(args.spec)
    if args.workers is not None and args.workers < 1:
        raise SweepError(f"--workers must be at least 1, got {args.workers}")
    limit = MAX_POINTS if args.max_points is None else args.max_points
    if limit < 1:
        raise SweepError(f"--max-points must be at least 1, got {limit}")
    total = check_size(spec, limit)
    client = None
    if args.scheduler is not None:
        _check_address(args.scheduler)
        try:
            from distributed import Client
        except ImportError:
            raise SweepError('--scheduler needs Dask: pip install "interlock[sweep]"') from None
        _check_address_with_dask(args.scheduler)
        try:
            client = Client(args.scheduler, timeout=10)
        except OSError as error:
            raise SweepError(f"no Dask scheduler at {args.scheduler}: {error}") from None
        except (ValueError, TypeError) as error:  # distributed's words for an address it cannot parse
            raise SweepError(f"--scheduler {args.scheduler!r} is not a Dask scheduler address ({error}); give "
                             "one such as tcp://10.0.0.5:8786") from None
    try:
        with tqdm(total=total, desc="sweep", unit="point", disable=None) as bar, \
                warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", SweepWarning)
            records = run(spec, args.output, executor=client, workers=args.workers, resume=args.resume,
                          progress=bar.update, max_points=limit)
    finally:
        if client is not None:
            client.close()
    for warning in caught:  # a damaged record, skipped: one line each; other warnings as Python shows them
        if issubclass(warning.category, SweepWarning):
            print(f"interlock sweep: warning: {warning.message}", file=sys.stderr)
        else:
            warnings.showwarning(warning.message, warning.category, warning.filename, warning.lineno)
    counts = Counter(r["status"] for r in records)
    print(f"{len(records)} points ({', '.join(f'{n} {s}' for s, n in sorted(counts.items()))}): {args.output}")
    for verdict in spec.verdicts:
        words = Counter(r["verdicts"].get(verdict) for r in records if r["status"] == "ok")
        print(f"  {verdict}: " + ", ".join(f"{n} {w}" for w, n in sorted(words.items())))
    if len(spec.parameters) == 2:
        from interlock.sweep.map import verdict_map

        x, y = (p.name for p in spec.parameters)
        output = Path(args.output)
        for verdict in spec.verdicts:
            try:
                path = verdict_map(records, x, y, verdict, output.with_name(f"{output.stem}-{verdict}.png"),
                                   theory=spec.theory(x, y))
            except SweepError as error:  # e.g. matplotlib missing: the records are the result
                print(f"  no map: {error}", file=sys.stderr)
                break
            print(f"  map: {path}")
    if records and not counts["ok"]:
        first = records[0]
        print(f"interlock sweep: no point succeeded; point {first['index']} is {first['status']}: {first['message']}",
              file=sys.stderr)
        return 1
    return 0


def _check_address_with_dask(address: str) -> None:
    """Refuse an address Dask's own parser rejects (an unknown scheme, no port, a port that is no number) before
    a Client starts its event loop for it: what a Client would say, without a thread to wait on."""
    from distributed.comm.addressing import parse_address
    from distributed.comm.registry import get_backend

    from interlock.sweep import SweepError

    try:
        scheme, location = parse_address(address, strict=False)
        if scheme != "inproc":  # in-process addresses have no host and port
            get_backend(scheme).get_address_host_port(location)
    except (ValueError, TypeError) as error:
        raise SweepError(f"--scheduler {address!r} is not a Dask scheduler address ({error}); give one such as "
                         "tcp://10.0.0.5:8786") from None


def _check_address(address: str) -> None:
    """Refuse what is plainly no scheduler address before Dask tries it for its 10 s: an empty one, one with
    spaces, a port outside 1-65535."""
    from interlock.sweep import SweepError

    port = address.rpartition(":")[2].rstrip("/")
    number = port.lstrip("+-")
    out_of_range = number.isascii() and number.isdigit() and not 0 < int(port) < 65536
    if not address.strip() or any(c.isspace() for c in address) or out_of_range:
        raise SweepError(f"--scheduler {address!r} is not a Dask scheduler address; give one such as "
                         "tcp://10.0.0.5:8786 (ports 1-65535)")
