"""The apps: what a reader opens on the compendium's results.

==================  =================================================================
``book``            ``make book``: the published book (Sphinx, MyST-NB) from what is committed
``explore``         ``make explore``: the interactive explorer (Panel); its models in
                    ``explore_model``
``bench``           ``make bench``: the speed targets, measured beside the peers
``lab``             ``make lab``: JupyterLab at the repository root
==================  =================================================================

They read the science, the papers and what the workflow records; nothing imports them.
"""
