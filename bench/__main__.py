"""Run every benchmark and print its figures beside a baseline measured in the same run (where one exists)."""

import sys

from bench import (animation_check, batch_compile, bvh_speed, contexter_speed, laban_effort, learning_protocol,
                   long_doodles, matcher_speed, performers, real_gestures, render_speed, replay_latency,
                   segmenter_speed, stages_accuracy, startup, stylize_signatures, stylize_speed, terrain_speed)


def main() -> int:
    print("Spatial motion doodles — benchmarks\n")
    startup.main([])
    print()
    segmenter_speed.main()
    print()
    real_gestures.main()
    print()
    performers.main()
    print()
    matcher_speed.main()
    print()
    bvh_speed.main()
    print()
    stages_accuracy.main()
    print()
    terrain_speed.main()
    print()
    stylize_speed.main()
    print()
    stylize_signatures.main([])
    print()
    laban_effort.main()
    print()
    learning_protocol.main()
    print()
    replay_latency.main()
    print()
    render_speed.main()
    print()
    contexter_speed.main()
    print()
    animation_check.main()
    print()
    batch_compile.main([])
    print()
    long_doodles.main([])
    return 0


if __name__ == "__main__":
    sys.exit(main())
