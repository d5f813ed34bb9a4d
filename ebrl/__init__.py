"""Episode-based reinforcement learning with an intrinsic behaviour (Unemi 2000).

Standalone numpy: never imports a simulator. See ebrl.agent for a worked example.
"""
from ebrl import intrinsic
from ebrl.agent import Agent
from ebrl.config import Config, paper_config
from ebrl.memory import Memory
from ebrl.similarity import similarity

__all__ = ["Agent", "Config", "Memory", "paper_config", "similarity", "intrinsic"]
