"""Shared fixtures: the packaged reference parameter sets; deterministic property tests.

The ``slow`` marker: the tests listed in :data:`SLOW_MODULES` and :data:`SLOW_TESTS` take
most of the suite's time; ``make check`` runs the others (``pytest -m "not slow"``) and
``make test`` runs them all.
"""

import hashlib

import pytest
from hypothesis import settings

from motosim.params import HandlebarParameters, SharpParameters, load_parameters

# property tests draw the same examples on every run, so CI is reproducible
settings.register_profile("deterministic", derandomize=True, deadline=None)
settings.load_profile("deterministic")


SLOW_MODULES = frozenset(
    {
        "src/motosim/rt/check.py",
        "tests/integration/test_cli_faults.py",
        "tests/integration/test_cli_stops.py",
        "tests/integration/test_closed_loop.py",
        "tests/integration/test_hands_loop.py",
        "tests/integration/test_quiet_loop.py",
        "tests/integration/test_cueing_mpc_beats_washout.py",
        "tests/integration/test_cueing_road_preview.py",
        "tests/integration/test_handlebar_bandwidth.py",
        "tests/integration/test_integral_corner.py",
        "tests/integration/test_rt_offline.py",
        "tests/integration/test_rt_platform.py",
        "tests/integration/test_rt_plausibility.py",
        "tests/integration/test_shipped_campaign.py",
        "tests/integration/test_stack_golden.py",
        "tests/reference/identification/test_rig_targets.py",
        "tests/unit/cueing/test_cueing_persistence.py",
        "tests/unit/test_loop_analysis.py",
    }
)
"""Test files marked ``slow`` whole: most of their tests take over 0.2 s (closed-loop runs,
real-time runs against a rig, designs, campaigns)."""

SLOW_TESTS = frozenset(
    {
        "tests/integration/test_bad_input_corpus.py::test_the_design_fixture_has_the_keys_motosim_design_writes",
        "tests/integration/test_bad_input_corpus_commands.py::test_a_ten_million_row_log_is_refused_at_once",
        "tests/integration/test_bad_input_corpus_commands.py::test_damaged_files",
        "tests/integration/test_bad_input_corpus_commands.py::test_every_number_option_at_more_edges",
        "tests/integration/test_bad_input_corpus_commands.py::test_every_option_at_its_edges",
        "tests/integration/test_bad_input_corpus_commands.py::test_every_value_of_every_file",
        "tests/integration/test_campaign.py::test_cli_runs_reports_reruns_and_refuses_bad_files",
        "tests/integration/test_campaign.py::test_joblib_and_dask_give_the_serial_metrics",
        "tests/integration/test_campaign.py::test_series_in_zarr_equal_a_plain_simulate_and_resume_skips_them",
        "tests/integration/test_cli_cueing.py::test_cueing_writes_commands_figures_and_json",
        "tests/integration/test_cli_design.py::test_design_at_the_can_rate",
        "tests/integration/test_cli_design.py::test_design_json_and_file",
        "tests/integration/test_cli_design.py::test_design_with_a_latency_shows_the_margins_kept",
        "tests/integration/test_cli_estimate.py::test_estimate_writes_columns_and_reports_error",
        "tests/integration/test_cli_foundation.py::test_modes_table_and_plot",
        "tests/integration/test_cli_foundation.py::test_python_dash_m_and_a_light_help",
        "tests/integration/test_cli_identification.py::test_drive_option_overrides_the_columns",
        "tests/integration/test_cli_identification.py::test_excite_json_records_the_excitations_settings",
        "tests/integration/test_cli_identification.py::test_identify_recovers_table1_and_writes_a_usable_file",
        "tests/integration/test_cli_typical_options.py::test_an_atypical_option_warns_once_and_the_command_goes_on",
        "tests/integration/test_cli_typical_options.py::test_excite_warns_for_long_noisy_runs_and_refuses_absurd_ones",
        "tests/integration/test_fidelity.py::test_a_probe_within_the_dry_friction_is_refused",
        "tests/integration/test_fidelity.py::test_fidelity_command_chirp_still_there",
        "tests/integration/test_fidelity.py::test_fidelity_command_json",
        "tests/integration/test_fidelity.py::test_friction_free_stack_measured_as_the_linear_analysis_predicts",
        "tests/integration/test_fidelity.py::test_handlebar_renders_the_virtual_steer_closer_with_feedforward",
        "tests/integration/test_hands_lockstep.py::test_lockstep_reads_the_torque_sensor_as_offline",
        "tests/integration/test_hands_lockstep.py::test_lockstep_rig_holds_the_handlebar_with_the_riders_hands",
        "tests/integration/test_rt_cli.py::test_a_fall_fades_the_torque_out_and_ends_the_run_with_exit_3",
        "tests/integration/test_rt_cli.py::test_a_run_reads_the_rigs_torque_sensor",
        "tests/integration/test_rt_cli.py::test_ctrl_c_fades_the_torque_out_and_closes_the_files",
        "tests/integration/test_rt_cli.py::test_rig_keeps_a_status_latency_that_run_takes_paced_by_the_bus",
        "tests/integration/test_rt_cli.py::test_rt_check_json",
        "tests/integration/test_rt_cli.py::test_run_against_the_rig_in_another_process",
        "tests/integration/test_rt_cli.py::test_run_paced_by_the_rigs_status_frames",
        "tests/integration/test_rt_cli.py::test_run_with_the_view_serves_live_rows_and_its_buttons_go_through_the_safety_stage",
        "tests/integration/test_rt_cli.py::test_the_platform_file_and_address_are_parsed_once",
        "tests/integration/test_rt_cli.py::test_the_rigs_virtual_rider_steers_by_the_runs_state_stream",
        "tests/integration/test_rt_cli_startup_interrupt.py::test_ctrl_c_while_the_rig_is_built_stops_it",
        "tests/integration/test_rt_compiled_wait.py::test_the_warm_ups_before_each_deadline_change_nothing_and_can_be_turned_off",
        "tests/integration/test_rt_link.py::test_the_fast_link_drops_its_own_frames_in_the_kernel",
        "tests/integration/test_rt_link.py::test_the_fast_link_hears_only_its_own_group",
        "tests/integration/test_view_cli.py::test_view_serves_the_result_until_interrupted",
        "tests/reference/control/test_control_fixed_order_reference.py::test_first_order_on_skogestad_example_9_3",
        "tests/reference/control/test_control_fixed_order_reference.py::test_first_order_reaches_full_order_optimum_on_handlebar",
        "tests/reference/identification/test_recovery.py::test_default_method_recovers_handlebars_unlike_table1",
        "tests/reference/identification/test_recovery.py::test_gradient_law_frictions_within_5_percent",
        "tests/reference/identification/test_recovery.py::test_least_squares_interval_and_rls_agree",
        "tests/unit/control/test_control_fixed_order.py::test_mimo_first_order",
        "tests/unit/control/test_control_fixed_order.py::test_static_and_second_order_controllers",
        "tests/unit/control/test_control_hinf_norm.py::test_finite_peak_just_below_feedthrough_level_is_not_missed",
        "tests/unit/control/test_control_hinf_norm.py::test_properties_dual_similarity_and_lower_bound",
        "tests/unit/control/test_control_torque_feedback.py::test_a_lighter_handlebar_is_held_as_stiffly_from_1_khz",
        "tests/unit/control/test_control_torque_feedback.py::test_first_order_within_2_percent_of_full_order",
        "tests/unit/control/test_control_torque_feedback.py::test_integral_corner_trades_phase_for_stiffness",
        "tests/unit/control/test_control_torque_feedback.py::test_the_packaged_handlebar_keeps_its_default_design",
        "tests/unit/control/test_control_torque_feedback.py::test_the_raise_is_bounded_at_twice_the_default",
        "tests/unit/cueing/test_cueing_mpc_huber.py::test_beyond_the_corner_the_plan_chases_the_roll_rate_less",
        "tests/unit/cueing/test_cueing_mpc_huber.py::test_ctrl_c_taken_by_osqp_during_a_solve_interrupts_the_cueing",
        "tests/unit/cueing/test_cueing_pipeline.py::test_mpc_false_cue_constraint_keeps_an_unprompted_roll_below_threshold",
        "tests/unit/cueing/test_cueing_pipeline.py::test_mpc_force_false_cue_band_holds_back_a_sustained_roll",
        "tests/unit/cueing/test_cueing_pipeline.py::test_mpc_holds_a_sustained_lateral_force_and_lets_a_roll_transient_fade",
        "tests/unit/cueing/test_cueing_pipeline.py::test_mpc_on_abrupt_and_noisy_motion_stays_finite_and_within_limits",
        "tests/unit/cueing/test_cueing_pipeline.py::test_no_limit_violation_and_a_roll_cue_in_phase",
        "tests/unit/cueing/test_cueing_preview.py::test_a_tilt_drawn_after_the_road_straightens_is_felt_less_with_the_terminal_rows",
        "tests/unit/cueing/test_cueing_preview.py::test_the_preview_fades_with_the_lean_asked_and_where_untrusted_is_the_causal_plan",
        "tests/unit/rt/test_can_codec.py::test_codec_agrees_with_cantools_both_ways",
        "tests/unit/rt/test_can_codec.py::test_compiled_codec_agrees_with_cantools_both_ways",
        "tests/unit/rt/test_can_codec.py::test_compiled_codec_is_the_python_codec",
        "tests/unit/rt/test_can_codec.py::test_udp_multicast_datagrams_are_read_as_python_can_packs_them",
        "tests/unit/rt/test_clock_loop.py::test_check_timing_on_a_simulated_clock_is_exact",
        "tests/unit/rt/test_clock_loop.py::test_privileges_are_reported_not_raised",
        "tests/unit/rt/test_safety.py::test_nothing_the_stage_sends_pushes_a_handlebar_too_fast_faster",
        "tests/unit/test_cli_bad_inputs.py::test_campaign_refuses_an_out_folder_holding_another_commands_result",
        "tests/unit/test_cli_light.py::test_the_wait_left_out_or_python_passes_silently_paced_by_the_bus_or_on_python_can",
        "tests/unit/test_cli_light.py::test_udp_multicast_options_left_out_pass_silently_with_another_bus",
        "tests/unit/test_docs.py::test_python_blocks_run",
        "tests/unit/test_motorcycle.py::test_straight_running_speed",
        "tests/unit/test_opendrive.py::test_the_view_draws_the_road_the_rider_follows",
        "tests/unit/test_report.py::test_report",
        "tests/unit/test_report.py::test_report_of_a_realtime_run_stopped_by_a_safety_fault",
        "tests/unit/test_report.py::test_report_of_an_interrupted_run",
        "tests/unit/test_report_figures.py::test_the_workers_draw_the_report_the_calling_process_draws",
        "tests/unit/test_results_faults.py::test_a_second_run_of_the_same_folder_is_refused",
        "tests/unit/test_results_faults.py::test_write_whole_removes_a_killed_writers_leftover_and_keeps_a_running_ones",
        "tests/unit/test_stack.py::test_recorded_layout_recompiles_when_the_signal_table_changes",
        "tests/unit/test_design_cache.py::test_warm_designs_a_scenario_so_that_its_run_designs_nothing",
        "tests/unit/test_design_cache.py::test_after_warm_a_new_process_compiles_nothing",
    }
)
"""Tests marked ``slow`` one by one (every parametrisation of each), in files that are fast
otherwise."""

UNMARKED_SLOW = 2.0
"""A test outside both lists that runs longer than this [s] is named at the end of a
``-m "not slow"`` run (``make check``), to be added to them."""


@pytest.fixture(autouse=True)
def _design_cache(
    request: pytest.FixtureRequest,
    tmp_path_factory: pytest.TempPathFactory,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Each test its own design cache (motosim.io.cache), made only when a design is stored:
    no test reads a design another test stored (one that patches a design function sees it
    called, whatever the order), and none touches the user's cache; the commands a test
    runs inherit it."""
    base = tmp_path_factory.getbasetemp()
    name = hashlib.sha1(request.node.nodeid.encode()).hexdigest()[:16]
    monkeypatch.setenv("MOTOSIM_CACHE_DIR", str(base / "design-cache" / name))


@pytest.fixture(scope="session")
def sharp() -> SharpParameters:
    """Sharp (1971) standard machine."""
    return load_parameters("sharp1971", "sharp")


@pytest.fixture(scope="session")
def handlebar() -> HandlebarParameters:
    """SIMACOM handlebar, Table I of Nehaoua, Arioui & Mammar (2012)."""
    return load_parameters("simacom_handlebar", "handlebar")


def _is_slow(item: pytest.Item) -> bool:
    path, _, name = item.nodeid.partition("::")
    return path in SLOW_MODULES or f"{path}::{name.split('[')[0]}" in SLOW_TESTS


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    for item in items:
        if _is_slow(item):
            item.add_marker(pytest.mark.slow)


_unmarked_slow: list[tuple[str, float]] = []


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    if report.when == "call" and report.duration > UNMARKED_SLOW and "slow" not in report.keywords:
        _unmarked_slow.append((report.nodeid, report.duration))


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    for nodeid, duration in _unmarked_slow:
        terminalreporter.write_line(
            f"{nodeid} took {duration:.1f} s: if it does on a second run too (the first test"
            " to compile the stack takes the compile), add it to SLOW_TESTS in tests/conftest.py"
        )
