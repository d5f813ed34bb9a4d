"""Episode-based reinforcement learning (Unemi 2000), standalone numpy."""
from ebrl import intrinsic
from ebrl.agent import Agent
from ebrl.config import Config, paper_config
from ebrl.similarity import similarity

__all__ = ["Agent", "Config", "paper_config", "similarity", "intrinsic"]
