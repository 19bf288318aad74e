// The events of AssignEvent: a thread of the assembly waits on the FIFO's event in canemud's
// shared memory (canChannelWaitRxEvent and the like) and sets the program's event whenever the
// FIFO's condition holds, then waits for the program to read (or write) before it looks again,
// so that a level that stays reached sets the event once per read and never spins.
using System;
using System.Threading;

namespace Ixxat.Vci3
{
  internal sealed class FifoEvent : IDisposable
  {
    readonly Func<uint, uint> wait;  // timeout in ms -> VCI_OK when the condition holds
    readonly object gate = new object();
    EventWaitHandle target;
    Thread thread;
    long generation;  // counts the program's reads or writes
    volatile bool stop;

    public FifoEvent(Func<uint, uint> wait) { this.wait = wait; }

    internal static EventWaitHandle Check(WaitHandle e, string what)
    {
      if (e == null) throw new VciException(Native.E_INVALIDARG, what + ".AssignEvent: the event is null");
      var ev = e as EventWaitHandle;
      if (ev == null)
        throw new VciException(Native.E_INVALIDARG, what + ".AssignEvent: " + e.GetType().Name +
                               " cannot be signalled; pass an AutoResetEvent or a ManualResetEvent");
      return ev;
    }

    public void Assign(EventWaitHandle e)
    {
      lock (gate)
      {
        target = e;
        if (thread != null) return;
        thread = new Thread(Run) { IsBackground = true, Name = "vci-fifo-event" };
        thread.Start();
      }
    }

    // The program read or wrote: the condition may have changed.
    public void Touched()
    {
      lock (gate) { generation++; Monitor.PulseAll(gate); }
    }

    void Run()
    {
      while (!stop)
      {
        uint hr = wait(50);
        if (stop) return;
        if (hr == Native.VCI_OK)
        {
          lock (gate)
          {
            long seen = generation;
            target.Set();
            while (!stop && generation == seen) Monitor.Wait(gate, 100);
          }
        }
        else if (hr != Native.E_TIMEOUT) Thread.Sleep(50);
      }
    }

    public void Dispose()
    {
      Thread t;
      lock (gate) { stop = true; Monitor.PulseAll(gate); t = thread; }
      if (t != null && t != Thread.CurrentThread) t.Join();
    }
  }
}
