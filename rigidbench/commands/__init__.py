"""The ``rigidbench`` verbs, one module each: ``arguments(sub)`` adds the verb's subparser and ``main(args)`` runs
it, returning its exit status (`rigidbench.exits`).

`rigidbench.cli` builds the parser from every verb's `arguments` (light: only argparse at the top of each module)
and imports nothing of the simulation until a verb's `main` runs. Options several verbs share (the settings, the
jobs, a sweep's grid) and the helpers they share are in `rigidbench.commands.shared`.
"""

# In the order `rigidbench --help` lists them.
VERBS = ("list", "run", "derivatives", "sweep", "frontier", "census", "power", "compare", "report", "render")
