"""python -m roughcontact.studies.open_questions {regenerate,publish} ...: docs/open-questions/."""

from .page import main

if __name__ == "__main__":
    main()
