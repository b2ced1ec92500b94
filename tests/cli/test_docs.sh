#!/usr/bin/env bash
# test_docs.sh -- every iird command that README.md, docs/cli.md and docs/deploy.md show runs as
# written: the lines of their ```sh blocks that start with `build/iird` or `iird` (trailing comments dropped), with
# the binary under test, from a scratch folder that looks like a fresh clone (a `scenes` link, no
# out/), so relative paths resolve as for a reader. Each is made quick, otherwise unchanged: the
# values of --size, --spp, --ref-spp, --frames and --rays are replaced, and --size, --frames,
# --ref-spp and --rays added where the subcommand takes them whatever the method (never a method
# parameter the line lacks). `serve` gets --port 0 and is stopped with SIGTERM once it prints its
# "serving" line; `make` lines are not run. Every command must exit 0, and an --out it names must
# exist afterwards. Usage: test_docs.sh IIRD SOURCE_DIR
set -u
iird=$(realpath "$1") # the commands run from another folder
src=$(realpath "$2")
. "$(dirname "$0")/lib.sh" docs

work=$tmp/clone
mkdir -p "$work"
ln -s "$src/scenes" "$work/scenes"
unset XDG_CACHE_HOME IIR_SCENES IIR_WEB # bench's reference cache goes to out/refcache, as documented
export OMP_NUM_THREADS=2

# The iird lines of the shell blocks of a Markdown file, without trailing comments.
doc_commands() {
    awk '/^```(sh|bash|shell)[[:space:]]*$/ { inside = 1; next } /^```/ { inside = 0 } inside' "$1" |
        sed -e 's/[[:space:]]#.*$//' -e 's/[[:space:]]*$//' | grep -E '^(build/)?iird( |$)'
}

# set_opt NAME VALUE [add]: in args, replace the value of --NAME (--NAME V or --NAME=V); with
# `add`, append --NAME VALUE when it is absent.
set_opt() {
    local name=$1 value=$2 i
    for ((i = 0; i < ${#args[@]}; i++)); do
        if [ "${args[i]}" = "--$name" ] && [ $((i + 1)) -lt ${#args[@]} ]; then
            args[i + 1]=$value
            return
        fi
        if [ "${args[i]#--$name=}" != "${args[i]}" ]; then
            args[i]="--$name=$value"
            return
        fi
    done
    [ "${3:-}" = add ] && args+=("--$name" "$value")
}

# opt_value NAME: the value of --NAME in args, or nothing.
opt_value() {
    local i
    for ((i = 0; i < ${#args[@]}; i++)); do
        [ "${args[i]}" = "--$1" ] && [ $((i + 1)) -lt ${#args[@]} ] && echo "${args[i + 1]}"
        [ "${args[i]#--$1=}" != "${args[i]}" ] && echo "${args[i]#--$1=}"
    done
}

has_opt() { [ -n "$(opt_value "$1")" ]; }

# Shrinks the work of args (the words after the binary) by subcommand.
shrink() {
    case "${args[0]:-}" in
    render)
        has_opt merge || set_opt size 64x48 add
        set_opt spp 4
        has_opt anim && ! has_opt segment && set_opt frames 0:3 add
        ;;
    bench)
        set_opt size 64x48 add
        set_opt spp 2
        set_opt frames 0:2 add
        set_opt ref-spp 4 add
        ;;
    raybench)
        set_opt size 16x16 add
        set_opt spp 1 # a method parameter of pt: only where the line has it
        set_opt rays 20000 add
        ;;
    serve)
        set_opt size 64x48
        set_opt port 0 add
        ;;
    esac
}

# Starts `serve` in the background, waits for its "serving" line, stops it with SIGTERM; its exit
# code, with its output in $log.
run_serve() {
    "$@" >"$log" 2>&1 &
    local pid=$! i
    for ((i = 0; i < 300; i++)); do
        grep -q "serving" "$log" && break
        kill -0 $pid 2>/dev/null || break
        sleep 0.1
    done
    grep -q "serving" "$log" || echo "(no 'serving' line within 30 s)" >>"$log"
    kill -TERM $pid 2>/dev/null
    wait $pid
}

total=0
for doc in README.md docs/cli.md docs/deploy.md; do
    [ -f "$src/$doc" ] || {
        fail "$doc is missing"
        continue
    }
    while IFS= read -r line; do
        total=$((total + 1))
        case "$line" in
        *[\"\'\$\`\|\;\&\<\>\(\)\\\*\?]*)
            fail "$doc: cannot run '$line' word by word (quotes or shell syntax): keep doc commands plain"
            continue
            ;;
        esac
        read -ra words <<<"$line"
        args=("${words[@]:1}")
        shrink
        log=$tmp/cmd-$total.log
        t0=${EPOCHREALTIME/./}
        if [ "${args[0]:-}" = serve ]; then
            (cd "$work" && run_serve "$iird" "${args[@]}")
        else
            (cd "$work" && "$iird" "${args[@]}" >"$log" 2>&1 </dev/null)
        fi
        rc=$?
        ms=$(((${EPOCHREALTIME/./} - t0) / 1000))
        if [ $rc != 0 ]; then
            fail "$doc: '$line' (ran: iird ${args[*]}) exited $rc: $(tail -n 20 "$log")"
            continue
        fi
        out=$(opt_value out)
        if [ -n "$out" ] && [ ! -e "$work/$out" ] && [ ! -e "$out" ]; then
            fail "$doc: '$line' (ran: iird ${args[*]}) exited 0 but wrote no $out"
            continue
        fi
        echo "ok ($ms ms): $doc: $line"
    done < <(doc_commands "$src/$doc")
done
[ $total -gt 0 ] || fail "no iird commands found in the docs' shell blocks"

if [ $failures -gt 0 ]; then
    echo "$failures failure(s)"
    exit 1
fi
echo "all $total documented commands ran"
