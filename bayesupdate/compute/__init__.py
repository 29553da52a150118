"""Where and how work runs, below every layer that models anything; imports nothing above the
core (``errors``).

- ``executors``: the executor seam, serial and local processes (``SerialExecutor``,
  ``ProcessExecutor``, ``executor_or_serial``);
- ``dask``: the Dask executor (the optional extra ``bayesupdate[dask]``);
- ``settings``: which executor a run uses (``ComputeSettings``) and ``open_executor``;
- ``stop``: a run's stop request (``StopRequest``);
- ``blas``: the BLAS thread variables (``BLAS_THREAD_VARIABLES``);
- ``batch_rows``: products over a batch whose rows do not depend on the batch (``row_product``);
- ``cache``: the on-disk cache of computed arrays; ``progress``: progress lines and bars.

Nothing is imported here, so reading ``compute.blas`` (the CLI does, before numpy loads) loads
nothing else.
"""
