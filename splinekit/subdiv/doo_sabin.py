"""Doo-Sabin refinement (placeholder until implemented below)."""
