"""docs/environments/: a page per Gymnasium id, written by experiments.outputs.gym_pages
from the registry and the environments themselves; the committed pages are what it
writes now, so a changed space, default or version cannot leave a stale page."""
import gymnasium

import tasks
import tasks.gym
from experiments.outputs import gym_pages


def test_the_committed_pages_are_what_the_registry_makes_now(tmp_path):
    made = gym_pages.pages()
    committed = {p.name: p.read_text() for p in gym_pages.FOLDER.glob("*.md")}
    assert sorted(committed) == sorted(made) == sorted(f"{name}.md" for name in tasks.ROBOTS), \
        "docs/environments/ has a page too many or too few: python -m experiments.outputs.gym_pages"
    stale = [name for name, text in made.items() if committed[name] != text]
    assert not stale, f"docs/environments/{', '.join(stale)} stale: python -m experiments.outputs.gym_pages"
    assert sorted(p.name for p in gym_pages.write(tmp_path)) == sorted(made)


def test_a_page_states_its_ids_spaces_and_versions():
    """Read from the environment gymnasium.make makes, not typed."""
    for name in tasks.ROBOTS:
        text = (gym_pages.FOLDER / f"{name}.md").read_text()
        env = gymnasium.make(tasks.gym.env_id(name))
        assert text.startswith(f"# {env.spec.name} (`{tasks.gym.env_id(name)}`)")
        assert f"| Action space | `{env.action_space}` |" in text
        assert f"| Observation space | `{env.observation_space}` |" in text
        assert f"| `max_episode_steps` | `{env.spec.max_episode_steps}` |" in text
        for version in tasks.gym.VERSIONS:
            assert f"- v{version}: " in text
        assert f'gymnasium.make("{tasks.gym.env_id(name, 0)}")` warns' in text
        env.close()
