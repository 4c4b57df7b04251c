"""Paper code: what serves one chapter of the compendium and no reader's own work.

One module (or package) per paper, and one per own-data chapter; each holds that chapter's fits
to published values, typo analyses, reconstructions, checks of its notebook's parameters,
scorecard helpers and figures (with their captions, beside the code that draws them). They
import the science packages, never the workflow or the apps (:mod:`mtaccuracy.compendium`,
:mod:`mtaccuracy.apps`; ``tests/test_layering.py``).

=========================  ===================================================================
``parameters``             how a notebook's parameters are declared (``param``) and checked
``figure``                 a figure's caption (``Caption``), declared beside its drawing code
``printed``                the papers' printed numbers (``data/papers/``) and their precision
``zheng2024``              notebook 01: Zheng et al. 2024, PCE against MCS and LHS Sobol'
``rong``                   notebook 02: Rong et al., Sobol' indices and the 90 % rule
``guo2016``                notebook 03: Guo et al. 2016, Latin hypercube and Spearman ranking
``xu2022``                 notebook 04: Xu et al. 2022, thermal error, MLR and SVR
``xu2022_reconstruction``  notebook 04: the seeded reconstruction of the unpublished data
``yang2021``               notebook 05: Yang et al. 2021, four-point separation and the GA
``your_machine``           notebook 06: a reader's own machine
``your_spindle``           notebook 07: a reader's own spindle probe file
=========================  ===================================================================
"""
