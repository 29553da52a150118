"""``bayesupdate cache``: the on-disk cache of certified reduced bases (``compute.cache``)."""

import json

NAME = "cache"
HELP = "show or clear the on-disk cache of reduced bases (info | clear)"
DESCRIPTION = """The certified reduced basis of a model is kept on disk, keyed by everything it
depends on (the model's matrices and terms, the parameter box, the basis settings, the package
version), so that calibrate, sample and discover on the same model build it once.  A large
model's calibration and its full solve at the reference design are kept there too.

Folder: BAYESUPDATE_CACHE_DIR, else the platform's user cache folder (~/.cache/bayesupdate on
Linux); cap: BAYESUPDATE_CACHE_MAX_MB (default 2048), least recently used entries go first.
Any command with --no-cache (or BAYESUPDATE_NO_CACHE=1) neither reads nor writes it.

Examples:
  bayesupdate cache info
  bayesupdate cache info --json
  bayesupdate cache clear"""


def add_arguments(parser):
    parser.add_argument("action", choices=("info", "clear"), help="info: folder, entries, size")
    parser.add_argument("--json", action="store_true", help="print one JSON object")


def run(args) -> int:
    from bayesupdate.compute.cache import ArrayStore

    store = ArrayStore.from_environment(honour_off=False)
    if args.action == "clear":
        removed = store.clear()
        out = {"removed": removed, **store.info().as_dict()}
        text = f"removed {removed} entries from {out['directory']}"
        print(json.dumps(out) if args.json else text)
        return 0
    info = store.info()
    if args.json:
        print(json.dumps(info.as_dict()))
    else:
        print(
            f"cache {info.directory}: {info.entries} entries, {info.bytes / 2**20:.1f} MB "
            f"(cap {info.max_bytes / 2**20:.0f} MB)"
        )
    return 0
