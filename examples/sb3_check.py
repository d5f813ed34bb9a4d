"""Every Gymnasium id under Stable-Baselines3: SB3's env checker with its warnings as
errors, then PPO and SAC trained briefly through SubprocVecEnv (spawned workers) and
evaluated. A check of the plumbing, not of learning.

    pip install -e '.[sb3]'
    python examples/sb3_check.py --steps 256
"""
import argparse
import sys
import time
import warnings


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=256, help="training steps per algorithm and id")
    p.add_argument("--ids", default=None, help="comma-separated ids (default: every robot's)")
    args = p.parse_args(argv)
    import gymnasium
    import torch
    from stable_baselines3 import PPO, SAC
    from stable_baselines3.common.env_checker import check_env
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.evaluation import evaluate_policy
    from stable_baselines3.common.vec_env import SubprocVecEnv

    import tasks.gym
    torch.set_num_threads(1)  # small networks; the workers use the other cores
    ids = args.ids.split(",") if args.ids else [tasks.gym.env_id(r) for r in tasks.gym.ROBOTS]
    for env_id in ids:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # any warning of SB3's checker fails the check
            env = gymnasium.make(env_id)
            check_env(env)
            env.close()
        for algo in (PPO, SAC):
            started = time.perf_counter()
            venv = make_vec_env("tasks.gym:" + env_id, n_envs=2, seed=0,
                                env_kwargs={"max_episode_steps": 50},
                                vec_env_cls=SubprocVecEnv, vec_env_kwargs={"start_method": "spawn"})
            extra = {"n_steps": 64, "batch_size": 64} if algo is PPO else {
                "learning_starts": 64, "batch_size": 64, "buffer_size": 10_000}
            model = algo("MultiInputPolicy", venv, seed=0, verbose=0, **extra)
            model.learn(total_timesteps=args.steps)
            mean, _ = evaluate_policy(model, venv, n_eval_episodes=2)
            venv.close()
            print(f"{env_id:<22} {algo.__name__:<4} checker clean, trained {args.steps} steps, "
                  f"evaluated (reward {mean:.2f}) in {time.perf_counter() - started:.0f} s",
                  flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
