"""The ``gdimitate`` command line's commands, one module each: ``add(sub)`` adds the command's
parser, ``run(args)`` runs it and returns its exit status; :mod:`.common` holds what they share.
Scenario code, not API."""
