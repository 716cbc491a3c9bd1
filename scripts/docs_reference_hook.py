"""MkDocs hook (``hooks:`` in mkdocs.yml): the reference pages made from the code
(``bridge_node.reference``) join the site's files at every build, so the config, command
line, interface and stream references never drift from the code and are never edited by hand."""
from mkdocs.structure.files import File, Files

from bridge_node.reference.pages import REFERENCE_PAGES


def on_files(files: Files, config) -> Files:
    for path, make in REFERENCE_PAGES.items():
        files.append(File.generated(config, path, content=make()))
    return files
