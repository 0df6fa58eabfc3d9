# placeholder, filled in below
rule sensitivity:
    input:
        [],
