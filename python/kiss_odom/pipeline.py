"""``kiss-odom-pipeline``: kiss-icp 1.3.0's ``kiss_icp_pipeline`` command on kiss-odom's core.

Same arguments, dataloaders, config files and outputs (poses, ``result_metrics.log``,
``config.yml``) as ``kiss_icp_pipeline``; only the numerical backend differs (see
:mod:`kiss_odom.backend`). Needs kiss-icp 1.3.0 installed (``pip install kiss-odom[pipeline]``).
"""

from kiss_odom import backend


def main() -> None:
    backend.install()
    try:
        from kiss_icp.tools.cmd import run
    except ImportError as e:
        raise SystemExit(f"kiss-odom-pipeline needs kiss-icp 1.3.0 installed: {e}")
    run()


if __name__ == "__main__":
    main()
