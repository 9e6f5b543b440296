"""python -m roughcontact.studies.kappa_gap {regenerate,publish} ...: the κ-gap page."""

from .page import main

if __name__ == "__main__":
    main()
