"""Names vulture (tests/test_architecture.py, .ci/run) cannot see used, each with its reason.

Dataclass fields that users read from results, APIs called from outside our code (emcee calls a
move's ``propose``; ``models.get_model`` imports builders by name), the seed's tables, and
attributes a peer library reads.  Anything else vulture reports is dead code: delete it.
"""

# dataclass fields read by users (result records, documentation of kinds)
description  # EffectKind / EffectParameter: documents a kind (users' own too)
sensitivity  # Localization: g_perp per used mode, a result field for users
strain_by_element  # ModalEnergies: element-level strain energy (beams)
shell_kinetic  # ModalEnergies: kinetic energy share per shell element
shell_kinetic_density  # ModalEnergies: kinetic energy share per area
rigid_eigenvalues  # SparseModes: the rigid-body eigenvalues found (reported apart)
n_springs  # benchmarks/opensees_frame.OpenSeesBuild: what was put into OpenSees
# called from outside our code
pytest_collection_modifyitems  # tests/conftest.py: a pytest hook
_.propose  # inference/delayed_acceptance: emcee's Move API
build_shear_building_model  # models/__init__ registry: "module:function" strings
extended_model_from_result  # pipelines/model_source: public, named in results_io and README
assemble_coo  # fe/sparse_modal: public assembly helper
__getattr__  # inference/__init__, discovery/__init__: PEP 562, Python calls it for a lazy name
__dir__  # inference/__init__, discovery/__init__: PEP 562, dir() of the package
# the seed's tables (models/exhaust_paper.py holds them all; the README quotes them)
TABLE3_OPTIMUM_PAPER
EXPR_INITIAL_REPORTED
# attributes pyfe3d's shell probe reads (benchmarks/shell_speed.py)
_.n3
_.n4
_.c3
_.c4
_.init_k_KC0
_.init_k_M
split_z  # ema.run_groups.RunGroups: the z-scores of the cuts between run groups, a result field
_.writeable  # fe.assembly: numpy's ndarray.flags.writeable, set to make memoized arrays read-only
mac_v33  # pipelines.aircraft.ComparisonRow: JSON fields of demo --case aircraft (asdict)
mac_v42
mac_ours
mass_kind  # nastran.card_records.Layout: a field Layout.same compares by __dataclass_fields__
