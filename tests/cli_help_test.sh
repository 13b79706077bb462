#!/usr/bin/env bash
# The CLI as a Debian user meets it (apps/help.cc). Usage:
#   cli_help_test.sh ZWIDTH SRC COMPLETION MANPAGE
# Checked against CLI11's own rendering of the parser (each command's --help):
# - every option of every command sits in a topic, not in CLI11's catch-all
#   "Options" (there only -h,--help), so a flag added in apps/ gets its topic;
# - every command's --help shows an example, and every example runs (in the
#   pipeline's order, in one folder, Table I from the source tree);
# - the installed completion script is the one the parser generates now, and
#   bash, with it loaded, completes every command and every option of each
#   (no more, no fewer), and each value choice it offers is named in that
#   option's help;
# - man -l renders the page without warnings, with a section per command that
#   names every option of the command (skipped when help2man was absent).
set -uo pipefail
ZW=$(realpath "$1"); SRC=$(realpath "$2"); COMPLETION=$(realpath "$3"); MANPAGE=$(realpath -m "$4")
source "$SRC/tests/cli_lib.sh"

commands=$("$ZW" --help | awk '/^Subcommands:/{on=1; next} on && /^  [a-z]/{print $1} on && /^$/{on=0}')
[ "$(wc -w <<<"$commands")" -ge 10 ] && ok "zwidth --help lists $(wc -w <<<"$commands") commands" ||
  bad "zwidth --help lists too few commands: $commands"

# options COMMAND: every option name of the command's --help, one a line (-o and --output both).
options() {
  "$ZW" "$1" --help | grep -oE '^  (-[A-Za-z0-9],)?--[A-Za-z0-9][A-Za-z0-9-]*' | sed 's/^ *//' | tr ',' '\n' | sort -u
}
# ungrouped COMMAND: the options help prints under "Options:", but -h,--help.
ungrouped() {
  "$ZW" "$1" --help | awk '/^[A-Z][^:]*:$/{group=$0; next} group == "Options:" && /^  -/{print $1}' | grep -v -- '^-h,--help$'
}

for c in $commands; do
  u=$(ungrouped "$c")
  [ -z "$u" ] && ok "$c: every option has a topic" ||
    bad "$c: no topic for $(echo $u) (add a row to kOptionTopics in apps/help.cc)"
  n=$("$ZW" "$c" --help | awk '/^Examples:$/{on=1; next} on && /^  zwidth /' | grep -c "^  zwidth $c ")
  [ "$n" -ge 1 ] && ok "$c: --help shows $n example(s)" || bad "$c: --help shows no example"
done

# One default per option: an option that the pipeline's commands share (estimate's, fit's, run's,
# batch's) shows the same default in each, as CLI11 renders it (a fit that fixed 2 sections where
# run searched the order was this).
defaults() {  # --option=default, for the options whose help shows one
  "$ZW" "$1" --help | grep -oE '^  (-[A-Za-z0-9],)?--[A-Za-z0-9-]+ [A-Z:]+(\[[^]]*\])?=[^ ]+' |
    sed -E 's/^ *(-[A-Za-z0-9],)?//; s/ [A-Z:]+(\[[^]]*\])?=/=/' | sort -t= -k1,1
}
for pair in "estimate fit" "estimate run" "fit run" "fit batch" "run batch"; do
  set -- $pair
  shared=$(join -t= -j1 <(defaults "$1") <(defaults "$2") | wc -l)
  differ=$(join -t= -j1 <(defaults "$1") <(defaults "$2") | awk -F= '$2 != $3 {print $1 ": " $2 " against " $3}')
  [ "$shared" -ge 5 ] && [ -z "$differ" ] && ok "$1 and $2: the $shared options they share have one default" ||
    bad "$1 and $2 ($shared shared options) differ in defaults: $differ"
done

# Every example runs, as an argument vector (no shell), with Table I from the folder its help names.
cd "$T" || exit 1
echo '{"objects":[{"name":"soft","K":1,"B":0.001},{"name":"hard","K":80,"B":0.001}]}' >scene.json
# The pipeline's order (each example uses the files the ones before wrote), then any other
# command (by then log.h5, frf.csv and model.json exist).
order="excite simulate estimate fit compare validate boundary relay check export filter-sweep run"
for c in $order; do
  [[ " $(echo $commands) " == *" $c "* ]] || bad "the example order names $c, which zwidth has not"
done
for c in $order $(for c in $commands; do [[ " $order " == *" $c "* ]] || echo "$c"; done); do
  while read -r line; do
    read -ra argv <<<"$line"
    # Every path an example names (an argument with a '/') exists for this binary (issue 24).
    for a in "${argv[@]}"; do
      [[ $a == */* ]] || continue
      [ -e "$a" ] && ok "example path exists: $a" || bad "example names $a, absent for $ZW"
    done
    "$ZW" "${argv[@]:1}" >out.txt 2>err.txt; rc=$?
    # check exits 3 when an object is unstable: the example's scene has one.
    if [ $rc -eq 0 ] || { [ "$c" = check ] && [ $rc -eq 3 ]; }; then ok "example runs (exit $rc): $line"
    else bad "example exits $rc: $line"; tail -3 err.txt; fi
  done < <("$ZW" "$c" --help 2>/dev/null | awk '/^Examples:$/{on=1; next} on && /^  zwidth /{sub(/^  /, ""); print}')
done

# The completion script: current, and complete.
if cmp -s "$COMPLETION" <("$ZW" --bash-completion); then ok "the built completion equals zwidth --bash-completion"
else bad "$COMPLETION differs from zwidth --bash-completion (stale build?)"; fi
# complete WORDS...: what bash offers for the last word, one a line, sorted.
complete_words() {
  bash -c 'source "$1"; shift; COMP_WORDS=("$@"); COMP_CWORD=$(($# - 1)); _zwidth; printf "%s\n" "${COMPREPLY[@]}" | sort -u' \
    _ "$COMPLETION" "$@"
}
top=$( (echo "$commands"; "$ZW" --help | grep -oE '^  (-[a-z],)?--[a-z-]+' | sed 's/^ *//' | tr ',' '\n') | grep -v '^$' | sort -u)
got=$(complete_words zwidth "")
[ "$got" = "$top" ] && ok "completion of 'zwidth ': the $(wc -l <<<"$top") commands and options of zwidth --help" ||
  bad "completion of 'zwidth ': $(diff <(echo "$top") <(echo "$got") | grep '^[<>]' | tr '\n' ' ')"
for c in $commands; do
  want=$(options "$c"); got=$(complete_words zwidth "$c" -)
  [ "$(wc -l <<<"$want")" -ge 3 ] || { bad "$c --help lists fewer than 3 options: $want"; continue; }
  [ "$got" = "$want" ] && ok "completion of 'zwidth $c -': its $(wc -l <<<"$want") options" ||
    bad "completion of 'zwidth $c -': $(diff <(echo "$want") <(echo "$got") | grep '^[<>]' | tr '\n' ' ')"
  # Value choices: every word offered after an option is named in that option's help entry.
  for o in $(options "$c" | grep -- '^--'); do
    choices=$(complete_words zwidth "$c" "$o" "")
    [ -z "$choices" ] && continue
    entry=$("$ZW" "$c" --help | awk -v o="$o" '$1 ~ "(^|,)"o"$" {print; getline; print}')
    for w in $choices; do
      [ -e "$w" ] && continue  # a file of this folder (--reference: table1 or a file)
      grep -qw -- "$w" <<<"$entry" && ok "completion of '$c $o': '$w' is in its help" ||
        bad "completion of '$c $o' offers '$w', which its help does not name: $entry"
    done
  done
done

# The man page.
if [ ! -e "$MANPAGE" ]; then
  echo "skip: no man page at $MANPAGE (help2man absent at build time)"
else
  text=$(MANWIDTH=200 LC_ALL=C.UTF-8 man --warnings -l "$MANPAGE" 2>man_err.txt); rc=$?
  [ $rc -eq 0 ] && [ ! -s man_err.txt ] && ok "man -l renders the page ($(wc -l <<<"$text") lines), no warnings" ||
    { bad "man -l: exit $rc"; cat man_err.txt; }
  for c in $commands; do
    section=$(awk -v h="ZWIDTH $(tr a-z A-Z <<<"$c")" '$0 == h {on=1; next} on && /^[A-Z]/{on=0} on' <<<"$text")
    [ -n "$section" ] || { bad "man page: no section ZWIDTH ${c^^}"; continue; }
    # -h,--help is the top-level OPTIONS' (the command sections leave it out).
    missing=$(for o in $(options "$c" | grep -vxE -- '-h|--help'); do
                grep -qE -- "(^|[^A-Za-z0-9-])$o([^A-Za-z0-9-]|\$)" <<<"$section" || echo "$o"; done)
    grep -q "\$ zwidth $c " <<<"$section" && ok "man page: section ZWIDTH ${c^^} has an example" ||
      bad "man page: section ZWIDTH ${c^^} has no example"
    [ -z "$missing" ] && ok "man page: section ZWIDTH ${c^^} names its $(options "$c" | grep -cvxE -- '-h|--help') options" ||
      bad "man page: section ZWIDTH ${c^^} lacks $(echo $missing)"
  done
fi
# Every exit status the sources use is listed in --help and the man page's text (issue 24):
# main()'s returns, ExitStatus{N} of the commands, and 128+N of the signal handlers.
codes=$( { grep -ohE 'return [0-9]+;' "$SRC/apps/main.cc" | grep -oE '[0-9]+'
           grep -ohE 'ExitStatus\{[0-9]+\}' "$SRC"/apps/*.cc | grep -oE '[0-9]+'
           grep -ohE 'const int code = .*;' "$SRC"/apps/cmd_stability.cc | grep -oE '\? [0-9]+' | grep -oE '[0-9]+'
           echo 0
           grep -q '::raise(sig)' "$SRC/io/atomic_file.cc" && echo '128+N'; } | sort -u)
[ "$(wc -w <<<"$codes")" -ge 5 ] || bad "found too few exit statuses in the sources: $(echo $codes)"
help_status=$("$ZW" --help | awk '/^Exit status:/{on=1} on')
man_status=$("$ZW" --help-man | awk '/^\*Exit status\*/{on=1} on')
for c in $codes; do
  for where in help man; do
    text=$help_status; [ $where = man ] && text=$man_status
    grep -qE -- "(^|[ :;])${c/+/\\+} " <<<"$text" && ok "exit status $c in --$where" ||
      bad "exit status $c (used by the sources) not listed in zwidth's $where text"
  done
done
echo "passed $pass, failed $fail"
[ "$fail" -eq 0 ]
