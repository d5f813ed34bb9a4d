"""Stable-Baselines3's PPO on EBRL/TwoWheel-v1: trains through SubprocVecEnv, evaluates,
then renders one episode to an MP4.

    pip install -e '.[sb3]'        # stable-baselines3 and torch (a CPU build is enough)
    python examples/sb3_ppo.py --timesteps 20000 --out ppo_two_wheel.mp4

The workers are started with spawn and get the id in its module form,
"tasks.gym:EBRL/TwoWheel-v1", so Gymnasium imports tasks.gym in each of them (Gymnasium
1.x loads no plugins by itself). No process loads an OpenGL library until it renders a
frame (tasks.render), so torch and MuJoCo share a process safely; only this process
renders, after training. The reward is the paper's: 1 at the goal, 0 elsewhere, so a
short training reaches the goal rarely; the point here is the plumbing.
"""
import argparse
import sys

ENV_ID = "tasks.gym:EBRL/TwoWheel-v1"


def parse(argv):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--timesteps", type=int, default=20_000, help="PPO's training steps")
    p.add_argument("--envs", type=int, default=4, help="SubprocVecEnv workers")
    p.add_argument("--episode-steps", type=int, default=500,
                   help="steps before an episode is truncated (the robot's budget is 30,000)")
    p.add_argument("--eval-episodes", type=int, default=4)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", default="ppo_two_wheel.mp4", help="the rendered episode")
    args = p.parse_args(argv)
    for name in ("timesteps", "envs", "episode_steps", "eval_episodes"):
        if getattr(args, name) < 1:
            p.error(f"--{name.replace('_', '-')} must be positive")
    if not args.out.endswith(".mp4"):
        p.error("--out must end in .mp4")
    return args


def main(argv=None):
    args = parse(argv)
    import gymnasium
    import imageio.v2 as imageio
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.evaluation import evaluate_policy
    from stable_baselines3.common.vec_env import SubprocVecEnv, VecNormalize

    limit = {"max_episode_steps": args.episode_steps}
    venv = make_vec_env(ENV_ID, n_envs=args.envs, seed=args.seed, env_kwargs=limit,
                        vec_env_cls=SubprocVecEnv, vec_env_kwargs={"start_method": "spawn"})
    venv = VecNormalize(venv, norm_reward=False)  # readings 0..255, velocities: scaled
    torch.set_num_threads(1)  # a small network; the workers use the other cores
    model = PPO("MultiInputPolicy", venv, n_steps=max(8, min(256, args.timesteps // args.envs)),
                batch_size=64, seed=args.seed, verbose=0)
    model.learn(total_timesteps=args.timesteps)
    venv.training = False
    mean, sd = evaluate_policy(model, venv, n_eval_episodes=args.eval_episodes)
    venv.close()
    print(f"PPO after {args.timesteps:,} steps: reward {mean:.2f} +- {sd:.2f} per episode "
          f"over {args.eval_episodes} (1 = the goal reached)")

    env = gymnasium.make(ENV_ID, render_mode="rgb_array", **limit)
    obs, info = env.reset(seed=args.seed)
    writer = imageio.get_writer(args.out, fps=10, codec="libx264", pixelformat="yuv420p",
                                macro_block_size=16, ffmpeg_log_level="error")
    steps, done = 0, False
    try:
        writer.append_data(env.render())
        while not done:
            scaled = venv.normalize_obs({k: v[None] for k, v in obs.items()})
            action, _ = model.predict(scaled, deterministic=True)
            obs, reward, terminated, truncated, info = env.step(action[0])
            writer.append_data(env.render())
            steps, done = steps + 1, terminated or truncated
    finally:
        writer.close()
        env.close()
    print(f"episode: {steps} steps, goal {'reached' if info['is_success'] else 'not reached'}"
          f" -> {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
