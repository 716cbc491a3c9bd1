"""Reference pages made from the code's own definitions (the config's pydantic models, the
command line's argparse parsers, the links' sentence, PGN and register tables, the state
stream's message), so that the documentation cannot drift from the code. The docs site's
build hook (``scripts/docs_reference_hook.py``) writes them into the site."""
