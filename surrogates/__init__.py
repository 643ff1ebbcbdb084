"""Surrogate models trained on past evaluations; pre-screening of mutations."""
