"""Recipes: the model, recipe files, offline validation and the compiled data-package codec."""
