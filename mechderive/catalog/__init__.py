"""The textbook catalog: the chapter's claims, each checked against the toolkit's derivations."""

from .registry import Claim, ClaimResult, Outcome, all_claims, register, run_claims

__all__ = ["Claim", "ClaimResult", "Outcome", "all_claims", "register", "run_claims"]
