"""The workflows a user runs, one module each: a validated study or settings record in, a frozen
result record out.

Layers (each imports only those before it)::

    core       errors, units, atomic, modal_data, model_protocol, correlation, paper (tables),
               parallel
    fe, ema    (ema imports no fe)
    models, inference   (inference sees models only through model_protocol)
    discovery  (uses inference and the FE layer)
    config     the study file's schema (knows discovery's settings record)
    pipelines  this package
    edge       commands/, cli, report/, the plots modules: argument parsing, printing, figures

Modules:
    study         ``prepare(study)``: model, data, problem, likelihood, checked before any work
    model_source  every kind of model source (built-in, Nastran deck, user function, discovery
                  result file)
    surrogates    the certified reduced basis a built-in FE model is calibrated and sampled on
    calibrate     ``run_calibration``: the multi-start optimum
    sample        ``run_sampling``: optimum, posterior, diagnostics, predictions (checkpointed)
    simulate      ``simulate_test``: a virtual roving-hammer test of a model with a hidden truth
    identify      ``read_frf_files`` + ``identify_frfs``: FRF files of one test -> modes, notes
    discover      ``discover_study``: what physics the model is missing
    demo          ``run_demo``: the seed's whole story (figures and report are made at the edge)

Pipelines may write the data files a run produces (result HDF5 with checkpoints, UFF, modes);
figures, reports and terminal output belong to the edge.
"""
