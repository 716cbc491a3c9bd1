import sys

from bridge_node.cli import main

sys.exit(main())
