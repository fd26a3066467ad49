#!/bin/sh
# help_defaults.sh TOOL SUBCOMMAND OPTION...: TOOL [SUBCOMMAND] --help exits 0 and every OPTION's
# line shows its default (CLI11 2.1: "--radius FLOAT:POSITIVE=0.025", later: "[0.025]"); a flag nobody defines exits 2, the usage code
# of every primlabel binary. SUBCOMMAND "-" is none.
tool=$1 sub=$2
shift 2
[ "$sub" = - ] && sub=
help=$("$tool" $sub --help) || { echo "$tool $sub --help failed"; exit 1; }
status=0
for option in "$@"; do
  line=$(printf '%s\n' "$help" | grep -E -- "^ +(-[A-Za-z], )?$option[ ,]" | head -n 1)
  if ! printf '%s\n' "$line" | grep -Eq -- "$option [^=]*=[^ ]|$option .*\[[^] ]+\]"; then
    echo "$tool: $option shows no default in --help: '$line'"
    status=1
  fi
done
"$tool" $sub --no-such-option-anywhere >/dev/null 2>&1
code=$?
[ "$code" -eq 2 ] || { echo "$tool: an unknown option exits $code, not 2"; status=1; }
exit $status
