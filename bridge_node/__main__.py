import sys

from bridge_node.commands.cli import main

sys.exit(main())
