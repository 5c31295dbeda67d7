"""The command line's commands, one module each (``mirrorlab.cli`` only builds the parser
from them and dispatches): ``NAME``, ``add_parser(subparsers)`` adding the command's
subparser with its arguments, and ``run(args)`` doing its work, returning the exit status.
:mod:`mirrorlab.commands.arguments` holds the arguments several commands share."""
