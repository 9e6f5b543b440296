"""python -m roughcontact.studies.reproduction {regenerate,publish} ...: the reproduction page."""

from .page import main

if __name__ == "__main__":
    main()
