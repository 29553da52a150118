"""CLI sub-commands, one module each (see ``bayesupdate.cli``)."""
