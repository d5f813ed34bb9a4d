"""Episode-based reinforcement learning (Unemi 2000): numpy, with the agent's per-step
work compiled by numba (ebrl.kernels). ebrl never imports the simulator.

Paper equation -> the function that computes it -> the tests that check it against a
case computed by hand (in tests/test_ebrl_equations.py unless named otherwise):

eq 1      W += alpha (S - W)          kernels.eq1 (also agent.eq1), applied by kernels.advance
          test_eq1_recall_weight_moves_alpha_of_the_way, test_recall_eq1_by_hand
2.2       recall table: the N_r       kernels.recall_since (kernels.fill); the act's
          largest weights             acting.recall_bounded, the same table bit for bit
                                      test_recall_eq1_by_hand; test_ebrl_memory.py:
                                      test_recall_selection_is_the_stable_top_n_r;
                                      test_recall_bounded.py
eq 2      S = 1 - sqrt(sum ... / 2n)  kernels.similarities (kernels.radicands, then
                                      kernels.similarity_of's sums); ebrl.similarity
                                      (the float64 reference, as printed)
          test_eq2_by_hand[reference], test_eq2_by_hand[compiled],
          test_compiled_similarity_equals_float64_reference,
          test_agent_similarity_equals_reference
eq 3-4    weighted modalities         the same two functions
          test_eq3_eq4_weighted_modalities_by_hand[reference], [compiled]
eq 2 V_i  variance of the memory      kernels.update_variance (running sums, floored)
          test_ebrl_memory.py: test_invariants_under_random_episodes,
          test_forgetting_takes_the_least_reliable_and_splices_links
eq 5      max_i min(W_i, U_i)         kernels.eq5 (also agent.eq5), kernels.policy
          test_eq5_measure_is_min_of_weight_and_utility, test_eq5_policy_by_hand,
          test_policy_threshold_and_empty_table_use_the_fallback
eq 6      U_j += r gamma^(t - t_j)    kernels.eq6
          test_eq6_utilities_discount_along_the_episode_and_stop_at_cutoff,
          test_eq6_exponent_is_elapsed_time_across_a_spliced_gap
eq 7      R += rho r (1 - R) / rho r R  kernels.eq7
          test_eq7_reliability_along_backward_links_both_signs
2.1       time discount R *= 0.99     kernels.time_discount
          test_eq7_reliability_along_backward_links_both_signs (the decays by hand)
2.1       forgetting the least        kernels.least_reliable, kernels.forget
          reliable element            test_ebrl_memory.py:
                                      test_forgetting_takes_the_least_reliable_and_splices_links,
                                      test_forgetting_takes_the_first_of_equal_reliabilities
eq 8      avoidance by turning        intrinsic.eq8, via intrinsic.avoid_by_turning ("eq8")
          test_eq8_two_wheel_avoidance_by_hand
eq 9-10   avoidance by accelerating   intrinsic.eq9, intrinsic.eq10, via
                                      intrinsic.avoid_by_accelerating ("eq9-10")
          test_eq9_eq10_floating_avoidance_by_hand
4         eq 8 and eq 9-10 as one     behaviour.Turning, behaviour.Accelerating (genomes,
          point of two families       JSON; `ebrl run --behaviour`, `ebrl evolve`)
                                      tests/test_evolve.py

acting.act chains eq 1-5 for one act and steps.learn_step stores the step and applies eq
6-7 and the time discount; ebrl.Agent holds the memory as one record (steps.AgentRecord)
and calls steps.act_memory and steps.learn_step once each per step (steps.end_trial at a
trial's end).

Readings with a credible alternative are switches: Config fields whose values are
listed in config.READINGS, the first Config's default (a protocol's readings may choose
another: tasks.protocols, docs/interpretation.md); tests in tests/test_ebrl_readings.py.

episode              trial / continuing        steps.end_trial via Agent.end_trial
                                               (keeps or cuts the link)
                     test_episode_continuing_keeps_the_link_across_a_trial_end,
                     test_episode_continuing_lets_eq7_cross_a_trial_end
recall_at_trial_end  empty / keep              steps.end_trial via Agent.end_trial
                     test_recall_table_kept_or_emptied_at_a_trial_end
eq7_scope (eq 7)     to_start / decided_only   kernels.eq7, kernels.eq7_decided via
                                               steps.learn_step; steps.act_memory sets
                                               the flags
                     test_eq7_scope_to_start_or_decided_only,
                     test_eq7_decided_only_counts_an_element_once_and_forgets_its_flag
forgetting (2.1)     least_reliable / oldest   kernels.least_reliable, kernels.oldest
                                               via steps.learn_step
                     test_forgetting_least_reliable_or_oldest,
                     test_oldest_kernel_takes_the_smallest_time_stamp
eq9_dead_zone        keep / zero               intrinsic.Intrinsic (hold) and
  (eq 9)                                       intrinsic.avoid_by_accelerating(previous)
                     test_eq9_dead_zone_keep_repeats_the_previous_acceleration,
                     test_eq9_keep_is_reset_by_the_agent_at_a_trial_end_and_ignored_by_eq8
random_in_avoidance  replace / add             intrinsic.Intrinsic
  (3.4)              test_random_in_avoidance_add_is_avoidance_plus_random_clipped
initial_reliability  a number in [0, 1]        steps.learn_step
                     test_initial_reliability_sets_the_forgetting_order
eq7_signal (eq 7)    reward / surprise_measure steps.act_memory (steps.expected_reward),
                     / surprise_rate           steps.eq7_signal via steps.learn_step
                     test_eq7_signal_by_hand
eq7_walk (eq 7)      whole / discounted / cut  kernels.eq7
                     test_eq7_walks_by_hand
forgetting_link      join / cut                kernels.forget
  (2.1)              test_forgetting_joins_or_cuts_the_episode
recall_candidates    all / past                kernels.recall_since (via acting.act)
  (2.2)              test_recall_candidates_past_only_by_hand
exploration (2.3)    fallback / random         steps.act_memory
                     test_exploration_reading_by_hand
The defaults reproduce the agent from before the switches bit for bit:
test_defaults_reproduce_the_agent_before_the_switches (against stored digests).

Section 4's other learners, behind the same interface (ebrl.baselines, tested in
tests/test_baselines.py; baselines.AGENTS names them): QTable, tabular Q-learning with
roulette-wheel selection, whose confidence is the variance of its action probabilities;
MFEC, model-free episodic control, trusted where its nearest neighbours are near.

This package's own import is light (numpy at most): `Config`, `paper_config` and
`similarity` are imported with it; `Agent` and the modules `intrinsic`, `baselines` and
`behaviour`, which compile with numba, at their first use (module __getattr__), so the
registries (ebrl.readings, ebrl.config) import without numba.
"""
import importlib

from ebrl.config import Config, paper_config
from ebrl.similarity import similarity

#: The names imported at their first use: {name: (module, attribute or None for the module)}.
_COMPILED = {"Agent": ("ebrl.agent", "Agent"), "intrinsic": ("ebrl.intrinsic", None),
             "baselines": ("ebrl.baselines", None), "behaviour": ("ebrl.behaviour", None)}

__all__ = ["Agent", "Config", "paper_config", "similarity", "intrinsic", "baselines", "behaviour"]


def __getattr__(name):
    """Agent and the numba modules (see the module): imported here at their first use."""
    if name not in _COMPILED:
        raise AttributeError(f"module 'ebrl' has no attribute {name!r}")
    module, attribute = _COMPILED[name]
    found = importlib.import_module(module)
    return getattr(found, attribute) if attribute else found


def __dir__():
    return sorted(set(globals()) | set(_COMPILED))
